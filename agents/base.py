"""The agent interface: batch-native selection policies.

An agent acts on the single env and on the vector env alike. It is reset from the
reset observation, chooses actions from an observation and learns from the step's
observation and reward::

    agent = agents.make_agent("mg-crb-cl", scenario, seed=0)
    obs, info = env.reset(seed=0)
    agent.reset(obs)
    while True:
        action = agent.act(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        agent.update(obs, reward)

:class:`agents.Rollout` runs this loop (and attaches the env to an oracle agent).
Observations with a leading trial axis (vector env) give actions (B, M + N);
unbatched observations (single env) give actions (M + N,). An agent sees only the
observation and the scenario's public geometry (station positions, Ms, Ns, target
weights, the radar constants); only an oracle reads the truth, through
``oracle_action()`` of the env it is attached to.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario, load_scenario
from mimo_radar_env.core.arrays import NUMPY, NumpyNamespace, TorchNamespace, namespace
from mimo_radar_env.core.counter_hash import Stream
from mimo_radar_env.core.streams import TrialRandom
from mimo_radar_env.core.superarm import masks_to_actions, top_mask
from mimo_radar_env.envs.device_forms import check_device_mode

from .costs import BOOKKEEPING, SOLVER, Cost, Needs
from .solvers import SuperArmSolver, make_solver

Observation = dict[str, NDArray[Any]]


def ucb_bonus(scale: float, t: int, counts: NDArray[np.float64]) -> NDArray[np.float64]:
    """The UCB bonus ``sqrt(scale ln t / d[m, n])`` (B, M, N) of eq18 / UCB1."""
    return namespace(counts).sqrt(scale * np.log(t) / counts)


def fuse_targets(weights: NDArray[np.float64], per_target: NDArray[np.float64]) -> NDArray[np.float64]:
    """eq34: ``I[m, n] = sum_k Omega_k I[k, m, n]``, (B, M, N) from (B, K, M, N)."""
    xp = namespace(per_target)
    return xp.einsum("k,bkmn->bmn", xp.asarray(weights, dtype=np.float64), per_target)


def blend_samples(
    predicted: NDArray[np.float64],
    played: NDArray[np.bool_],
    sample: NDArray[np.float64],
    weight: float | NDArray[np.float64],
) -> NDArray[np.float64]:
    """eq14's update: played channels ``(1 - w) Y_bar + w gamma``, the others ``Y_bar``
    (estimates (B, K, M, N), ``played`` (B, M, N))."""
    blended = (1.0 - weight) * predicted + weight * sample
    return namespace(predicted).where(played[:, None], blended, predicted)


class Agent(ABC):
    """Base class of selection policies.

    Parameters
    ----------
    scenario : Scenario or str
        The scenario (its public geometry is all an agent may use).
    seed : int, optional
        Seed of the agent's random streams: trial ``i`` of a batch draws from ``seed + i``
        (:class:`~mimo_radar_env.core.streams.TrialRandom`), as trial ``i`` of the vector env does.
    **keywords
        The fields of :attr:`keyword_parameters`, where the class declares one (its instance is
        ``self.parameters``); a class without one takes no other keyword (``TypeError``).
    """

    #: Registry name.
    name: ClassVar[str] = ""
    #: A dataclass of keyword parameters declared once and shared by several agents (say,
    #: MG-CRB-CL's estimator parameters); the registry lists its fields beside the signature's.
    keyword_parameters: ClassVar[type | None] = None
    #: What it needs from the env (:class:`~agents.costs.Needs`), and the parts of its cost
    #: (:mod:`agents.costs`): declarations the rollout loop and the harness read.
    needs: ClassVar[Needs] = Needs()
    costs: ClassVar[tuple[Cost, ...]] = (BOOKKEEPING,)

    def __init__(self, scenario: Scenario | str, seed: int | None = None, **keywords: Any) -> None:
        if self.keyword_parameters is None and keywords:
            raise TypeError(f"{type(self).__name__}() got unexpected keyword argument(s) {sorted(keywords)}")
        self.parameters = None if self.keyword_parameters is None else self.keyword_parameters(**keywords)
        self.scenario = load_scenario(scenario) if not isinstance(scenario, Scenario) else scenario
        self.random = TrialRandom(seed)
        self.num_tx = self.scenario.num_tx
        self.num_rx = self.scenario.num_rx
        self.tx_count = self.scenario.tx_per_step
        self.rx_count = self.scenario.rx_per_step
        self.weights = self.scenario.weights
        self.batch_size = 0
        self.t = 0
        #: the form it acts in on torch (:meth:`use_device_mode`)
        self.device_mode = "eager"
        #: the array namespace of the observations it acts on (:mod:`mimo_radar_env.core.arrays`):
        #: numpy, or torch on the device of an env made with ``device=``; set by :meth:`reset`
        self.xp: NumpyNamespace | TorchNamespace = NUMPY

    # -------------------------------------------------------- public API
    def reset(self, obs: Observation) -> None:
        """Start an episode from the reset observation (every channel probed once)."""
        batch, _ = self._batch(obs)
        if self.needs.tracking and ("track" not in batch or "track_pred" not in batch):
            raise ValueError(
                f"{self.name} reads the tracker's estimates from the observation: "
                "make the env with tracking=True"
            )
        self.batch_size = batch["sinr"].shape[0]
        self.xp = namespace(batch["sinr"])
        sc = self.scenario
        if tuple(batch["sinr"].shape[1:]) != (sc.num_targets, sc.num_tx, sc.num_rx):
            raise ValueError(
                f"{self._label} was made for scenario {sc.name!r} (K={sc.num_targets} "
                f"targets, M={sc.num_tx}, N={sc.num_rx}), and the observation's 'sinr' has shape "
                f"{tuple(batch['sinr'].shape[1:])} per trial: make the agent with the env's scenario"
            )
        self._check_finite(batch)
        if self.xp.is_torch and not self.needs.device:
            raise ValueError(
                f"{self._label} acts on numpy arrays only, and this observation is "
                f"torch's on {self.xp.device}: make its env with device=None (agents that run on a "
                "device declare needs = Needs(device=True))"
            )
        self.random.reset(self.batch_size, self.xp)
        self.t = 0
        self._reset(batch)

    def act(self, obs: Observation) -> NDArray[np.int8]:
        """The action for the coming step."""
        batch, batched = self._episode_batch(obs, "act")
        self.t += 1
        actions = self._act(batch)
        return actions if batched else actions[0]

    def use_device_mode(self, device_mode: str) -> None:
        """Act in form ``device_mode`` on torch (``"eager"``, ``"graph"``, ``"compiled"``:
        :mod:`mimo_radar_env.envs.device_forms`), as its env steps: in ``"compiled"``, what has a
        compiled form (BPSO's iteration) runs through ``torch.compile``; the same selections in
        every form. A :class:`~agents.rollout.Rollout` sets its env's."""
        check_device_mode(device_mode)
        self.device_mode = device_mode

    def env_option_values(self) -> dict[str, Any]:
        """Its parameters named after env options (``needs.env_option_params``) and their values,
        which must equal its env's (a :class:`~agents.rollout.Rollout` checks them): its attributes
        of those names, unless a subclass says otherwise."""
        missing = [key for key in self.needs.env_option_params if not hasattr(self, key)]
        if missing:
            raise TypeError(
                f"{type(self).__name__} declares env_option_params {missing} but has no such attributes: "
                "set them in __init__, or override env_option_values()"
            )
        return {key: getattr(self, key) for key in self.needs.env_option_params}

    def update(self, obs: Observation, reward: Any) -> None:
        """Learn from the observation and reward of the step just taken; ``ValueError`` naming
        the key of an observation entry (or the reward) that is not finite."""
        batch, _ = self._episode_batch(obs, "update")
        values = self.xp.reshape(self.xp.asarray(reward, dtype=np.float64), (-1,))
        if values.shape[0] != self.batch_size:
            raise ValueError(
                f"{self._label}: the reward must hold one value per trial ({self.batch_size}), "
                f"got shape {tuple(np.shape(reward))}"
            )
        self._check_finite({**batch, "reward": values})
        self._update(batch, values)

    def _check_finite(self, entries: Observation) -> None:
        xp = self.xp
        floats = {key: value for key, value in entries.items() if xp.dtype_kind(value) == "f"}
        if xp.is_torch and floats:  # one read of the device for all of them, the culprit after
            if bool(xp.torch.stack([xp.all(xp.isfinite(value)) for value in floats.values()]).all()):
                return
        for key, value in floats.items():
            if not bool(xp.all(xp.isfinite(value))):
                raise ValueError(f"{self._label}: the {key!r} it was given is not finite")

    # ------------------------------------------------------- to implement
    def _reset(self, obs: Observation) -> None:
        """Start an episode (default: nothing to remember)."""
        return None

    @abstractmethod
    def _act(self, obs: Observation) -> NDArray[np.int8]: ...

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        """Learn from a step (default: nothing to learn)."""
        return None

    # ------------------------------------------------------------ helpers
    @property
    def _label(self) -> str:
        return self.name or type(self).__name__

    def __repr__(self) -> str:
        made = f"{type(self).__name__} {self._label!r} on {self.scenario.name!r}, seed {self.random.seed}"
        episode = f"reset on {self.batch_size} trial(s), step {self.t}" if self.batch_size else "not reset"
        return f"<{made}, {episode}>"

    def _episode_batch(self, obs: Observation, call: str) -> tuple[Observation, bool]:
        """The batched observation of a step of the episode ``reset`` began: as many trials."""
        if self.batch_size == 0:
            raise RuntimeError(f"{type(self).__name__}.{call}() called before reset(obs)")
        batch, batched = self._batch(obs)
        size = batch["sinr"].shape[0]
        if size != self.batch_size:
            given = f"{size} trial(s)" if batched else "one trial (no trial axis)"
            raise ValueError(
                f"{self._label} was reset on {self.batch_size} trial(s), and this observation holds "
                f"{given}: give it the observations of the env it was reset on"
            )
        return batch, batched

    def _batch(self, obs: Observation) -> tuple[Observation, bool]:
        if not isinstance(obs, Mapping) or "sinr" not in obs:
            keys = f"keys {sorted(obs)}" if isinstance(obs, Mapping) else type(obs).__name__
            raise ValueError(f"{self._label} acts on the env's dict observation, with key 'sinr'; got {keys}")
        sinr = obs["sinr"] if namespace(obs["sinr"]).is_torch else np.asarray(obs["sinr"])
        if sinr.ndim == 3:
            return {key: np.asarray(value)[None] for key, value in obs.items()}, False
        if sinr.ndim == 4:
            return obs, True
        raise ValueError(f"observation 'sinr' must have shape (K, M, N) or (B, K, M, N), got {sinr.shape}")

    def actions_from_masks(self, tx: NDArray[np.bool_], rx: NDArray[np.bool_]) -> NDArray[np.int8]:
        return masks_to_actions(tx, rx)

    def random_super_arms(self, count: int) -> NDArray[np.int8]:
        """``count`` uniformly random valid super arms, (count, M + N)."""
        if count != self.random.batch_size:
            raise ValueError(f"random super arms are drawn per trial: {self.random.batch_size}, got {count}")
        tx = top_mask(self.random.uniform(Stream.AGENT_RANDOM_TX, (self.num_tx,)), self.tx_count)
        rx = top_mask(self.random.uniform(Stream.AGENT_RANDOM_RX, (self.num_rx,)), self.rx_count)
        return self.actions_from_masks(tx, rx)


class IndexPolicy(Agent):
    """An agent that plays the super arm maximising ``sum_{(m, n) in A} I[m, n]``.

    The base owns what every index policy keeps: the play counts ``counts`` ``d[m, n]``
    (B, M, N) and the SINR estimates ``estimate`` ``Y_hat[k, m, n]`` (B, K, M, N), both
    initialised by the reset observation (every channel probed once), the step counter
    ``t``, and the super-arm solver. Each step:

    1. :meth:`predict`: the estimates carried to the coming step, ``Y_bar(t)`` (restless
       policies such as MG-CRB-CL's eq16 move them; the default keeps them);
    2. :meth:`compute_index`: the fused index of the coming step from ``Y_bar(t)``
       (:meth:`index` is the same as a pure query);
    3. the solver picks the super arm;
    4. after the step, played channels blend their new sample in:
       ``Y_hat = (1 - w) Y_bar + w gamma`` with ``w`` = :meth:`step_size`; the others keep
       ``Y_bar``; ``counts = discount * counts + played``.

    A policy writes its index (``compute_index``) and, where it differs from the default,
    its prediction, step size and count discount.

    Parameters
    ----------
    solver : str or SuperArmSolver
        ``"exact"`` (default for the baselines), ``"bpso"`` or ``"alternating"``.
    solver_params : dict, optional
        Parameters of the solver (``{"population": 50}``...).
    """

    default_solver: ClassVar[str] = "exact"
    costs: ClassVar[tuple[Cost, ...]] = (BOOKKEEPING, SOLVER)
    #: Multiplies the play counts every step (1: plain counts; < 1: discounted counts).
    count_discount: float = 1.0

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        solver: str | SuperArmSolver | None = None,
        solver_params: dict[str, Any] | None = None,
        **keywords: Any,
    ) -> None:
        super().__init__(scenario, seed, **keywords)
        if solver_params is not None and not isinstance(solver_params, dict):
            raise ValueError(f"solver_params must be a mapping of solver parameters, got {solver_params!r}")
        self.solver = make_solver(
            solver or self.default_solver, self.tx_count, self.rx_count, **(solver_params or {})
        )
        self.solver.check_layout(self.scenario.num_tx, self.scenario.num_rx)

    def use_device_mode(self, device_mode: str) -> None:
        super().use_device_mode(device_mode)
        self.solver.device_mode = device_mode

    # -------------------------------------------------------------- state
    def _reset(self, obs: Observation) -> None:
        self.estimate = self.xp.astype(self.xp.copy(obs["sinr"]), np.float64)  # Y_hat(0)
        self.counts = self.xp.astype(self.xp.copy(obs["probed"]), np.float64)  # d(0)
        self.predicted = self.estimate

    def predict(self, obs: Observation) -> NDArray[np.float64]:
        """``Y_bar(t)``: the estimates carried to the coming step (default: unchanged)."""
        return self.estimate

    def step_size(self, counts: NDArray[np.float64]) -> float | NDArray[np.float64]:
        """Weight of a new sample in the estimate, given the updated counts (default: sample mean)."""
        return 1.0 / self.xp.maximum(counts, 1.0)[:, None]

    def index(self, obs: Observation) -> NDArray[np.float64]:
        """The fused index (B, M, N) for the coming step ``self.t``: a query that changes no
        estimate or count (sampling policies draw from the agent's generator)."""
        return self.compute_index(self.predict(obs), obs)

    @abstractmethod
    def compute_index(self, predicted: NDArray[np.float64], obs: Observation) -> NDArray[np.float64]:
        """The fused index (B, M, N) from the predicted estimates ``Y_bar(t)`` (B, K, M, N)."""

    # --------------------------------------------------------------- loop
    def _act(self, obs: Observation) -> NDArray[np.int8]:
        self.predicted = self.predict(obs)
        tx, rx = self.solver.solve(self.compute_index(self.predicted, obs), self.random)
        return self.actions_from_masks(tx, rx)

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        played = self.xp.astype(obs["probed"], bool)
        sample = self.xp.astype(obs["sinr"], np.float64)
        self.counts = self.count_discount * self.counts + played  # eq15 (1.0 * d is exact)
        self.estimate = blend_samples(self.predicted, played, sample, self.step_size(self.counts))

    def fuse(self, per_target: NDArray[np.float64]) -> NDArray[np.float64]:
        """eq34: ``I[m, n] = sum_k Omega_k I[k, m, n]``."""
        return fuse_targets(self.weights, per_target)

    def bonus(self, scale: float) -> NDArray[np.float64]:
        """The UCB bonus ``sqrt(scale ln t / d[m, n])`` (B, M, N) of eq18 / UCB1."""
        return ucb_bonus(scale, self.t, self.counts)
