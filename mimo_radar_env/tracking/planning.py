"""Receding-horizon selection for tracking: sequences of super arms over the next H steps.

A plan is a sequence ``(A_1, ..., A_H)`` of super arms for steps ``t + 1 .. t + H``; its cost
is the summed criterion of the predicted posterior position covariances,
``sum_h sum_k Omega_k c(P_k(t + h | t + h))`` (``c``: trace, m^2, or log det). The covariance
is carried from step to step in the information form of the tracker's model:

* step ``t + 1`` starts from the tracker's predicted covariance ``P_bar`` (the IMM mixture);
* a super arm adds its channels' position information ``H' R^-1 H`` (at the forecast's
  predicted positions, with its variances) as the fusion does
  (:meth:`~.fusion.Fusion.planning_gain`);
* between steps the posterior is predicted with the constant-velocity model,
  ``P' = F P F' + Q``.

The cost of a step is the myopic criterion of :func:`~.selection.super_arm_criterion` on the
position block of the prior, which is what the position block of the full posterior is
(the measurements see only the position), so ``H = 1`` is best-tracking's selection exactly.
Plans are searched per trial, batched over trials:

* ``"beam"``: the ``width`` cheapest partial plans are kept at each depth and extended by every
  super arm (``width`` at least ``A^(H-1)`` is exhaustive);
* ``"rollout"``: every first super arm, each continued greedily (the one-step best at each
  later step);
* ``"mcts"``: Monte-Carlo tree search (UCT) with a budget of ``simulations`` per step over the
  ``candidates`` super arms of each node with the smallest one-step cost, each new node valued
  by the greedy continuation to the horizon; the plan follows the most visited children;
* ``"exhaustive"``: every sequence, up to :data:`MAX_EXHAUSTIVE_SEQUENCES` (tests' reference).

The first super arm of the cheapest plan is played (receding horizon).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..core.motion import POSITION, position_block
from ..core.superarm import all_super_arms, super_arm_count
from .fusion import fusion_class
from .information import inverse_2x2
from .selection import MAX_ENUMERATED_SUPER_ARMS, _check_choices, _per_target, super_arm_criterion

PLAN_SEARCHES = ("beam", "rollout", "mcts", "exhaustive")
#: The most sequences the exhaustive search scores per trial.
MAX_EXHAUSTIVE_SEQUENCES = 200_000


@dataclass(frozen=True)
class Forecast:
    """What a plan of a batch of trials is scored on.

    Attributes
    ----------
    covariance : array (B, K, 4, 4)
        The predicted covariance of step ``t + 1``.
    information : array (B, H, K, M, N, 2, 2)
        Each channel's position information at step ``t + h``.
    transition : array (4, 4) or (H, K, 4, 4)
        The motion that predicts the covariance from one planned step to the next: one for all
        steps and targets, or (the bound's) each target's true motion after each step.
    process_cov : array (4, 4)
    weights : array (K,)
        ``Omega``.
    """

    covariance: NDArray[np.float64]
    information: NDArray[np.float64]
    transition: NDArray[np.float64]
    process_cov: NDArray[np.float64]
    weights: NDArray[np.float64]

    @property
    def horizon(self) -> int:
        return self.information.shape[1]

    def first(self, steps: int) -> Forecast:
        """The forecast of the first ``steps`` steps only."""
        transition = self.transition if self.transition.ndim == 2 else self.transition[:steps]
        return Forecast(
            self.covariance, self.information[:, :steps], transition, self.process_cov, self.weights
        )

    def transition_after(self, h: int) -> NDArray[np.float64]:
        """The transition from planned step ``h`` (0-based) to the next: (4, 4) or (K, 4, 4)."""
        return self.transition if self.transition.ndim == 2 else self.transition[h]


def posterior_covariance(
    covariance: NDArray[np.float64],
    information: NDArray[np.float64],
    tx_mask: NDArray[np.bool_],
    rx_mask: NDArray[np.bool_],
    fusion: str,
) -> NDArray[np.float64]:
    """The full posterior covariance (S, K, 4, 4) after the channels ``tx_mask x rx_mask``
    ((S, M), (S, N)) with position information ``information`` (S, K, M, N, 2, 2), from the
    prior ``covariance`` (S, K, 4, 4), fused as ``fusion`` fuses: ``P - P E G E' P``
    (Woodbury's identity) with the fusion's gain ``G`` (:meth:`~.fusion.Fusion.planning_gain`:
    centralised, the gain of the summed information; eq22's average, the mean of each
    channel's gain)."""
    selected = (tx_mask[:, :, None] & rx_mask[:, None, :]).astype(np.float64)  # (S, M, N)
    gain = fusion_class(fusion).planning_gain(information, position_block(covariance), selected)
    cross = covariance[..., :, POSITION]  # P E: (S, K, 4, 2)
    return covariance - cross @ gain @ np.swapaxes(cross, -1, -2)


def smallest(values: NDArray[np.float64], keep: int) -> NDArray[np.int64]:
    """The indices of the ``keep`` smallest values of each row (B, n), smallest first and the
    first occurrence on ties: ``np.argsort(values, axis=1, kind="stable")[:, :keep]``, found by a
    partition (linear in ``n``) and a sort of the kept ones only."""
    n = values.shape[1]
    if keep >= n:
        return np.argsort(values, axis=1, kind="stable")
    threshold = np.take_along_axis(values, np.argpartition(values, keep - 1, axis=1)[:, keep - 1 : keep], 1)
    below = values < threshold
    tied = values == threshold
    room = keep - below.sum(axis=1, keepdims=True)
    chosen = below | (tied & (np.cumsum(tied, axis=1) <= room))  # exactly ``keep`` per row
    index = np.nonzero(chosen)[1].reshape(len(values), keep)  # ascending index in each row
    order = np.argsort(np.take_along_axis(values, index, 1), axis=1, kind="stable")
    return np.take_along_axis(index, order, 1)


class Planner:
    """The receding-horizon search of one layout (see the module's docstring).

    Parameters
    ----------
    num_tx, num_rx, tx_count, rx_count : int
        ``M``, ``N``, ``Ms``, ``Ns``: the super arms are all valid selections (at most
        :data:`~.selection.MAX_ENUMERATED_SUPER_ARMS` of them).
    search : str
        One of :data:`PLAN_SEARCHES`.
    width : int
        The beam's width.
    criterion, fusion : str
        As :func:`~.selection.select_for_tracking`.
    simulations, candidates : int
        MCTS's budget per step and the children of each node.
    """

    def __init__(
        self,
        num_tx: int,
        num_rx: int,
        tx_count: int,
        rx_count: int,
        search: str = "beam",
        width: int = 5,
        criterion: str = "trace",
        fusion: str = "centralized",
        simulations: int = 64,
        candidates: int = 8,
    ) -> None:
        _check_choices(criterion, fusion)
        for name, value, high in (("simulations", simulations, 100_000), ("candidates", candidates, 10_000)):
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= high:
                raise ValueError(f"{name} must be an integer in [1, {high}], got {value!r}")
        self.simulations, self.candidates = simulations, candidates
        if search not in PLAN_SEARCHES:
            raise ValueError(f"search must be one of {list(PLAN_SEARCHES)}, got {search!r}")
        if isinstance(width, bool) or not isinstance(width, int) or not 1 <= width <= 10_000:
            raise ValueError(f"width must be an integer in [1, 10000], got {width!r}")
        count = super_arm_count(num_tx, num_rx, tx_count, rx_count)
        if count > MAX_ENUMERATED_SUPER_ARMS:
            raise ValueError(
                f"planning scores every super arm at every step: at most {MAX_ENUMERATED_SUPER_ARMS:,} of "
                f"them, this layout has {count:,}"
            )
        self.tx_masks, self.rx_masks = all_super_arms(num_tx, num_rx, tx_count, rx_count)
        selected = self.tx_masks[:, :, None] & self.rx_masks[:, None, :]  # (A, M, N)
        self._selected = selected.reshape(len(selected), -1).T.astype(np.float64)  # (M N, A)
        self._channels = selected.sum(axis=(1, 2)).astype(np.float64)  # (A,)
        self.search, self.width, self.criterion, self.fusion = search, width, criterion, fusion

    @property
    def arms(self) -> int:
        return len(self.tx_masks)

    def check_horizon(self, horizon: int) -> None:
        if self.search == "exhaustive" and self.arms**horizon > MAX_EXHAUSTIVE_SEQUENCES:
            raise ValueError(
                f"the exhaustive search scores {self.arms}^{horizon} sequences, more than "
                f"{MAX_EXHAUSTIVE_SEQUENCES:,}: use search='beam' or 'rollout', or a shorter horizon"
            )

    def _costs(
        self, covariance: NDArray[np.float64], information: NDArray[np.float64], weights, first: bool = True
    ) -> NDArray:
        """The step's cost of every super arm from each state: (S, A) for priors (S, K, 4, 4).

        The plan's first step is scored by :func:`~.selection.super_arm_criterion` itself (so that
        ``H = 1`` is best-tracking's choice bit for bit); later steps by the same criterion with
        the channels' terms summed over each super arm by one matrix product (BLAS), which
        agrees with it to rounding (tested) and is several times faster."""
        if first:
            return super_arm_criterion(
                position_block(covariance),
                information,
                self.tx_masks,
                self.rx_masks,
                weights,
                self.criterion,
                self.fusion,
            )
        return self._fast_costs(covariance, information, weights)

    def _fast_costs(self, covariance, information, weights) -> NDArray:
        prior_info, _ = inverse_2x2(position_block(covariance))  # (S, K, 2, 2)
        posterior = fusion_class(self.fusion)
        terms = posterior.channel_terms(prior_info, information)  # (S, K, M, N, 2, 2)
        S, K = terms.shape[:2]
        flat = terms.reshape(S, K, -1, 4)  # (S, K, M N, 4)
        total = np.matmul(np.swapaxes(flat, -1, -2), self._selected)  # (S, K, 4, A)
        total = np.moveaxis(total, -1, 2).reshape(S, K, self.arms, 2, 2)
        count = self._channels[None, None, :, None, None]
        covariance_a = posterior.posterior_from_sum(prior_info[:, :, None], total, count)  # (S, K, A, 2, 2)
        return np.einsum(
            "k,ska->sa", np.asarray(weights, dtype=np.float64), _per_target(covariance_a, self.criterion)
        )

    def _advance(
        self,
        covariance: NDArray[np.float64],
        information: NDArray[np.float64],
        arms: NDArray[np.int64],
        forecast: Forecast,
        h: int,
    ) -> NDArray[np.float64]:
        """The prior of step ``h + 1`` of each state (S, K, 4, 4) after playing ``arms`` (S,) at
        step ``h``."""
        posterior = posterior_covariance(
            covariance, information, self.tx_masks[arms], self.rx_masks[arms], self.fusion
        )
        F = forecast.transition_after(h)
        return F @ posterior @ np.swapaxes(F, -1, -2) + forecast.process_cov

    def plan(self, forecast: Forecast) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """The cheapest plan of each trial: its super arms' indices (B, H) into
        :attr:`tx_masks`/:attr:`rx_masks` and its cost (B,)."""
        horizon = forecast.horizon
        self.check_horizon(horizon)
        if self.search == "mcts":
            return self._mcts(forecast)
        batch = forecast.covariance.shape[0]
        width = {"beam": self.width, "exhaustive": self.arms ** max(horizon - 1, 0), "rollout": self.arms}[
            self.search
        ]
        # the states: (B, S) partial plans with their prior for the next step and their cost
        covariance = forecast.covariance[:, None]
        cost = np.zeros((batch, 1))
        plans = np.zeros((batch, 1, 0), dtype=np.int64)
        for h in range(horizon):
            S = covariance.shape[1]
            info = np.repeat(forecast.information[:, h], S, axis=0)  # (B*S, K, M, N, 2, 2)
            step = self._costs(
                covariance.reshape(batch * S, *covariance.shape[2:]), info, forecast.weights, first=h == 0
            )
            total = cost[:, :, None] + step.reshape(batch, S, self.arms)  # (B, S, A)
            if self.search == "rollout" and h > 0:  # each plan continues with its one-step best
                arm = np.argmin(total, axis=2)  # (B, S)
                parent = np.broadcast_to(np.arange(S), (batch, S))
            else:
                flat = total.reshape(batch, S * self.arms)
                keep = min(width, flat.shape[1])
                order = smallest(flat, keep)
                parent, arm = np.divmod(order, self.arms)
            rows = np.arange(batch)[:, None]
            cost = total[rows, parent, arm]
            plans = np.concatenate([plans[rows, parent], arm[..., None]], axis=2)
            if h + 1 < horizon:
                kept = covariance[rows, parent]  # (B, S', K, 4, 4)
                S2 = kept.shape[1]
                covariance = self._advance(
                    kept.reshape(batch * S2, *kept.shape[2:]),
                    np.repeat(forecast.information[:, h], S2, axis=0),
                    arm.reshape(-1),
                    forecast,
                    h,
                ).reshape(kept.shape)
        best = np.argmin(cost, axis=1)
        rows = np.arange(batch)
        return plans[rows, best], cost[rows, best]

    def _step(self, covariance, forecast: Forecast, depth: NDArray[np.int64], rows: NDArray[np.int64]):
        """The one-step cost of every super arm (n, A) from priors ``covariance`` (n, K, 4, 4) of
        trials ``rows`` at steps ``depth`` (n,)."""
        first = bool(np.all(depth == 0)) if len(depth) else True
        if first or not np.any(depth == 0):
            return self._costs(covariance, forecast.information[rows, depth], forecast.weights, first=first)
        out = np.empty((len(rows), self.arms))
        for at_first in (True, False):
            pick = (depth == 0) == at_first
            out[pick] = self._costs(
                covariance[pick],
                forecast.information[rows[pick], depth[pick]],
                forecast.weights,
                first=at_first,
            )
        return out

    def _greedy_to_end(self, covariance, forecast: Forecast, depth, rows) -> NDArray[np.float64]:
        """The cost of continuing greedily from steps ``depth`` (n,) to the horizon, (n,)."""
        horizon = forecast.horizon
        total = np.zeros(len(rows))
        depth = depth.copy()
        live = depth < horizon
        while live.any():
            idx = np.flatnonzero(live)
            costs = self._step(covariance[idx], forecast, depth[idx], rows[idx])
            arm = np.argmin(costs, axis=1)
            total[idx] += costs[np.arange(len(idx)), arm]
            ahead = depth[idx] + 1 < horizon
            if ahead.any():
                sub = idx[ahead]
                covariance[sub] = self._advance_rows(
                    covariance[sub], forecast, depth[sub], rows[sub], arm[ahead]
                )
            depth[idx] += 1
            live = depth < horizon
        return total

    def _advance_rows(self, covariance, forecast: Forecast, depth, rows, arms) -> NDArray[np.float64]:
        """The next step's priors of states at different steps ``depth`` after ``arms``."""
        posterior = posterior_covariance(
            covariance,
            forecast.information[rows, depth],
            self.tx_masks[arms],
            self.rx_masks[arms],
            self.fusion,
        )
        if forecast.transition.ndim == 2:
            F = forecast.transition
        else:
            F = forecast.transition[depth]  # (n, K, 4, 4)
        return F @ posterior @ np.swapaxes(F, -1, -2) + forecast.process_cov

    def _mcts(self, forecast: Forecast) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """UCT over each trial's tree of partial plans, batched over trials (see the module)."""
        batch, horizon = forecast.covariance.shape[0], forecast.horizon
        k = min(self.candidates, self.arms)
        nodes = 1 + self.simulations
        every = np.arange(batch)
        cov = np.zeros((batch, nodes, *forecast.covariance.shape[1:]))
        cov[:, 0] = forecast.covariance
        depth = np.zeros((batch, nodes), dtype=np.int64)
        arms = np.zeros((batch, nodes, k), dtype=np.int64)  # each node's candidates, cheapest first
        step_cost = np.zeros((batch, nodes, k))
        child = np.full((batch, nodes, k), -1, dtype=np.int64)
        edge_visits = np.zeros((batch, nodes, k))
        edge_cost = np.zeros((batch, nodes, k))  # summed cost-to-go through the edge
        used = np.ones(batch, dtype=np.int64)

        def expand(rows, node):
            costs = self._step(cov[rows, node], forecast, depth[rows, node], rows)
            order = np.argsort(costs, axis=1, kind="stable")[:, :k]
            arms[rows, node] = order
            step_cost[rows, node] = np.take_along_axis(costs, order, axis=1)

        expand(every, np.zeros(batch, dtype=np.int64))
        scale = np.maximum(step_cost[:, 0, 0] * horizon, 1e-300)  # the exploration's unit: a plan's cost
        for _ in range(self.simulations):
            node = np.zeros(batch, dtype=np.int64)
            path_node = np.zeros((batch, horizon), dtype=np.int64)
            path_edge = np.zeros((batch, horizon), dtype=np.int64)
            length = np.zeros(batch, dtype=np.int64)
            tail = np.zeros(batch)  # the cost below the path's last edge
            active = np.ones(batch, dtype=bool)
            for d in range(horizon):
                idx = np.flatnonzero(active)
                if not len(idx):
                    break
                visits = edge_visits[idx, node[idx]]  # (n, k)
                mean = edge_cost[idx, node[idx]] / np.maximum(visits, 1)
                bonus = np.sqrt(2.0 * np.log(visits.sum(axis=1, keepdims=True) + 1.0) / np.maximum(visits, 1))
                score = np.where(visits > 0, -mean / scale[idx, None] + bonus, np.inf)
                edge = np.argmax(score, axis=1)  # unvisited first, cheapest first among them
                path_node[idx, d], path_edge[idx, d] = node[idx], edge
                length[idx] += 1
                nxt = child[idx, node[idx], edge]
                if d + 1 == horizon:
                    break
                new = nxt < 0
                if new.any():  # one new node per trial per simulation, valued by the greedy continuation
                    rows, parent, e = idx[new], node[idx[new]], edge[new]
                    created = used[rows]
                    used[rows] += 1
                    child[rows, parent, e] = created
                    depth[rows, created] = d + 1
                    cov[rows, created] = self._advance_rows(
                        cov[rows, parent], forecast, np.full(len(rows), d), rows, arms[rows, parent, e]
                    )
                    expand(rows, created)
                    tail[rows] = self._greedy_to_end(
                        cov[rows, created].copy(), forecast, depth[rows, created], rows
                    )
                    active[rows] = False
                keep = idx[~new]
                node[keep] = nxt[~new]
            # back up: each edge of the path gets its step's cost plus everything below it
            costs = step_cost[every[:, None], path_node, path_edge] * (np.arange(horizon) < length[:, None])
            below = np.cumsum(costs[:, ::-1], axis=1)[:, ::-1] + tail[:, None]
            for d in range(horizon):
                on = length > d
                rows = every[on]
                edge_visits[rows, path_node[on, d], path_edge[on, d]] += 1
                edge_cost[rows, path_node[on, d], path_edge[on, d]] += below[on, d]
        plans = self._most_visited(forecast, edge_visits, arms, child)
        return plans, plan_cost(self, forecast, plans[:, None])[:, 0]

    def _most_visited(
        self, forecast: Forecast, edge_visits: NDArray, arms: NDArray, child: NDArray
    ) -> NDArray[np.int64]:
        """The plan of each trial's tree: the most visited child at each depth, greedy where the
        tree ends (B, H)."""
        batch, horizon = forecast.covariance.shape[0], forecast.horizon
        every = np.arange(batch)
        plans = np.zeros((batch, horizon), dtype=np.int64)
        node = np.zeros(batch, dtype=np.int64)
        in_tree = np.ones(batch, dtype=bool)
        state = forecast.covariance.copy()
        for d in range(horizon):
            costs = self._step(state, forecast, np.full(batch, d), every)
            greedy = np.argmin(costs, axis=1)
            best = np.argmax(edge_visits[every, node], axis=1)
            visited = edge_visits[every, node, best] > 0
            use_tree = in_tree & visited
            plans[:, d] = np.where(use_tree, arms[every, node, best], greedy)
            nxt = child[every, node, best]
            in_tree = use_tree & (nxt >= 0)
            node = np.where(in_tree, nxt, 0)
            if d + 1 < horizon:
                state = self._advance_rows(state, forecast, np.full(batch, d), every, plans[:, d])
        return plans

    def first_arm(self, forecast: Forecast) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """The super arm to play now, masks (B, M), (B, N): the first of the cheapest plan."""
        plans, _ = self.plan(forecast)
        return self.tx_masks[plans[:, 0]], self.rx_masks[plans[:, 0]]


def sequences(arms: int, horizon: int) -> NDArray[np.int64]:
    """Every sequence of ``horizon`` arms out of ``arms``, (arms^horizon, horizon), in
    lexicographic order."""
    grids = np.indices((arms,) * horizon).reshape(horizon, -1).T
    return grids.astype(np.int64)


def plan_cost(planner: Planner, forecast: Forecast, plans: NDArray[np.int64]) -> NDArray[np.float64]:
    """The cost of given plans (B, P, H) of every trial, (B, P): the reference the searches are
    tested against (every plan scored on its own)."""
    batch, count, horizon = plans.shape
    covariance = np.repeat(forecast.covariance, count, axis=0)
    cost = np.zeros(batch * count)
    flat = plans.reshape(batch * count, horizon)
    rows = np.arange(batch * count)
    for h in range(horizon):
        info = np.repeat(forecast.information[:, h], count, axis=0)
        cost += planner._costs(covariance, info, forecast.weights, first=h == 0)[rows, flat[:, h]]
        covariance = planner._advance(covariance, info, flat[:, h], forecast, h)
    return cost.reshape(batch, count)


def position_traces(planner: Planner, forecast: Forecast, plan: NDArray[np.int64]) -> NDArray[np.float64]:
    """The trace of each target's posterior position covariance (m^2) at every step of one plan
    per trial (B, H): (B, H, K)."""
    covariance = forecast.covariance
    traces = []
    for h in range(plan.shape[1]):
        arms = plan[:, h]
        posterior = posterior_covariance(
            covariance,
            forecast.information[:, h],
            planner.tx_masks[arms],
            planner.rx_masks[arms],
            planner.fusion,
        )
        traces.append(posterior[..., 0, 0] + posterior[..., 2, 2])
        F = forecast.transition_after(h)
        covariance = F @ posterior @ np.swapaxes(F, -1, -2) + forecast.process_cov
    return np.stack(traces, axis=1)


def best_achievable_bound(
    forecast: Forecast, num_tx: int, num_rx: int, tx_count: int, rx_count: int, width: int = 5
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The offline bound on selection: given the whole truth (``forecast``: the PCRB's prior of
    the first step, every channel's information at the true positions with the true variances,
    each target's true motion), the selection sequence with the smallest time-averaged
    ``sum_k Omega_k`` PCRB position MSE that a beam of ``width`` finds over the whole horizon
    (the PCRB is a centralised bound: the channels' information adds). Returns each target's
    bound over the episode, ``sqrt(mean_t trace)`` (m), (B, K), as runs report theirs, and the
    sequence (B, H)."""
    planner = Planner(num_tx, num_rx, tx_count, rx_count, search="beam", width=width, fusion="centralized")
    plan, _ = planner.plan(forecast)
    return np.sqrt(position_traces(planner, forecast, plan).mean(axis=1)), plan
