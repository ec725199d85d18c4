"""The batch engine shared by the single env and the native vector env.

:class:`RadarEngine` runs B trials in lockstep: it checks actions, advances the
truth, probes the selected channels, runs the tracker and assembles the
observation and info dictionaries with a leading trial axis. The single env is
the B = 1 case and squeezes that axis; there is no second implementation.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from ..core.arrays import check_precision, device_namespace, float_precision, namespace
from ..core.geometry import channel_jacobian
from ..core.model import RadarModel
from ..core.motion import POSITION, position_block, positions, transition_matrix
from ..core.simulation import ChannelObservations, RadarSimulation
from ..core.streams import keys_from_generator
from ..core.superarm import best_super_arm, masks_to_actions, super_arm_value
from ..scenarios import Scenario
from ..tracking import IMMUKFTracker
from ..tracking.bound import bound_step, position_bound
from ..tracking.information import channel_information, jacobian_information, position_determinant
from ..tracking.planning import Forecast
from ..tracking.selection import select_for_tracking
from .cost import check_memory
from .device_forms import check_device_mode, make_forms
from .options import EnvOptions


def check_actions(actions: Any, expected_shape: tuple[int, ...]) -> NDArray[np.int8]:
    """Validate actions against ``MultiBinary``: shape, a real dtype, values 0/1 only.

    ``actions`` may be a numpy array (or anything ``np.asarray`` takes) or a torch tensor, checked
    where it lives. Raises ``ValueError`` naming what is wrong; returns the actions as int8.
    """
    xp = namespace(actions)
    arr = actions if xp.is_torch else np.asarray(actions)
    kind = xp.dtype_kind(arr)
    if kind not in "biuf":
        raise ValueError(f"action must be an array of 0/1 integers (MultiBinary), got dtype {arr.dtype}")
    if tuple(arr.shape) != expected_shape:
        raise ValueError(
            f"action must have shape {expected_shape} (first M bits choose transmitters, "
            f"the last N receivers), got shape {tuple(arr.shape)}"
        )
    if kind == "f" and not xp.all(xp.isfinite(arr)):
        raise ValueError("action contains NaN or infinite values; expected only 0 and 1")
    if not xp.all((arr == 0) | (arr == 1)):
        bad = np.unique(xp.to_numpy(arr[(arr != 0) & (arr != 1)]))[:5]
        raise ValueError(f"action values must be 0 or 1, got {bad.tolist()}")
    return xp.astype(arr, np.int8)


Method = TypeVar("Method", bound=Callable[..., Any])


def _in_precision(method: Method) -> Method:
    """Runs an engine method with its floats in the engine's precision (:func:`float_precision`)."""

    @functools.wraps(method)
    def run(self: RadarEngine, *args: Any, **kwargs: Any) -> Any:
        with float_precision(self.precision):
            return method(self, *args, **kwargs)

    return run  # type: ignore[return-value]


def true_indices(mask: NDArray[np.bool_], count: int) -> NDArray[np.int64]:
    """Indices of the first ``count`` True entries of each row, ascending."""
    xp = namespace(mask)
    return xp.sort(xp.argsort(~mask, axis=1, kind="stable")[:, :count], axis=1)


class RadarEngine:
    """B trials of ``MimoRadarSelect`` in lockstep.

    Parameters
    ----------
    options : EnvOptions
    scenario : Scenario
    batch_size : int
    device : None, or a torch device
        numpy (None) or torch on that device.
    device_mode : str
        The torch step's form (:mod:`.device_forms`): ``"eager"`` (default), ``"graph"`` or
        ``"compiled"``.
    precision : str
        ``"float64"`` (default) or, on torch only, ``"float32"``: faster on a device, not the
        same numbers (docs/performance.md gives the measured difference).
    """

    def __init__(
        self,
        options: EnvOptions,
        scenario: Scenario,
        batch_size: int,
        device: Any = None,
        device_mode: str = "eager",
        precision: str = "float64",
    ) -> None:
        check_device_mode(device_mode, device)
        check_precision(precision, device)
        self.precision = precision
        with float_precision(precision):
            self._build(options, scenario, batch_size, device, device_mode)

    def _build(
        self, options: EnvOptions, scenario: Scenario, batch_size: int, device: Any, device_mode: str
    ) -> None:
        self.xp = xp = device_namespace(device)
        self.device = xp.device
        self.options = options
        self.scenario = scenario
        check_memory(scenario, batch_size)
        if options.measurement_quality is not None:
            low, high = scenario.measurement_quality_range()
            if not low <= options.measurement_quality <= high:
                raise ValueError(
                    f"measurement_quality={options.measurement_quality:g} puts the measurement variances "
                    f"Sigma0 / lambda outside their physical ranges for scenario {scenario.name!r}; allowed: "
                    f"[{low:.3g}, {high:.3g}]"
                )
        self.model = RadarModel.from_scenario(scenario).to(xp)
        self.batch_size = batch_size
        self.simulation = RadarSimulation(
            self.model, batch_size, options.measurement_quality, options.lambda_scale, options.truth
        )
        self.tracker = (
            IMMUKFTracker(self.model, batch_size, fusion=options.fusion) if options.tracking else None
        )
        self.num_tx, self.num_rx = scenario.num_tx, scenario.num_rx
        self.action_size = self.num_tx + self.num_rx
        self.step_index = 0
        self.last_action = xp.zeros((batch_size, self.action_size), dtype=np.int8)
        self.last_valid = xp.zeros(batch_size, dtype=bool)
        self.invalid_steps = xp.zeros(batch_size, dtype=np.int64)  # this episode's, per trial
        self._warned_invalid = False
        self.device_mode = device_mode
        self._forms = make_forms(self, device_mode)

    @property
    def horizon(self) -> int:
        return self.scenario.horizon

    # ----------------------------------------------------------- episode
    def reset(
        self, generators: Sequence[np.random.Generator]
    ) -> tuple[dict[str, NDArray], dict[str, NDArray]]:
        """Start an episode in every trial; trial i draws its keys from ``generators[i]``."""
        return self.reset_from_keys(np.stack([keys_from_generator(g) for g in generators]))

    @_in_precision
    def reset_from_keys(self, keys: NDArray[np.uint64]) -> tuple[dict[str, NDArray], dict[str, NDArray]]:
        """Start an episode in every trial from its two keys (B, 2) (:func:`keys_from_generator`'s;
        a benchmark of many trials draws them once and starts from them again)."""
        xp = self.xp
        self.simulation.reset(keys)
        if self.tracker is not None:
            self.tracker.reset(self.simulation.initial_estimates)
            initial_cov = xp.asarray(np.stack([t.initial_covariance for t in self.scenario.targets]))
            self._bound_covariance = xp.broadcast_to(initial_cov, (self.batch_size, *initial_cov.shape))
        self.step_index = 0
        self.last_action = xp.zeros((self.batch_size, self.action_size), dtype=np.int8)
        self.last_valid = xp.zeros(self.batch_size, dtype=bool)
        self.invalid_steps = xp.zeros(self.batch_size, dtype=np.int64)
        sinr = self.simulation.sinr_samples_all()  # Algorithm 1: every channel probed once
        probed = xp.ones((self.batch_size, self.num_tx, self.num_rx), dtype=np.int8)
        obs = self._observation(sinr, probed)
        info = self._truth_info()
        return obs, info

    @_in_precision
    def step(self, actions: Any) -> tuple[dict[str, NDArray], NDArray, NDArray, NDArray, dict[str, NDArray]]:
        """Apply actions (B, M + N); returns obs, reward, terminated, truncated, info."""
        if self.step_index >= self.horizon:
            raise RuntimeError(f"the episode ended after {self.horizon} steps; call reset()")
        xp = self.xp
        actions = xp.asarray(check_actions(actions, (self.batch_size, self.action_size)))
        if self.options.invalid_action == "raise":
            self._refuse_invalid(actions)
        obs, reward, info = self._forms.step(actions) if self._forms is not None else self.advance(actions)
        self.step_index += 1
        self.simulation.step_index = self.step_index
        if self.step_index == self.horizon:
            self._warn_if_invalid_dominated()
        terminated = xp.zeros(self.batch_size, dtype=bool)
        truncated = xp.full(self.batch_size, self.step_index >= self.horizon)
        return obs, reward, terminated, truncated, info

    def _refuse_invalid(self, actions: Any) -> None:
        sc, xp = self.scenario, self.xp
        tx_count = actions[:, : self.num_tx].sum(axis=1)
        rx_count = actions[:, self.num_tx :].sum(axis=1)
        valid = (tx_count == sc.tx_per_step) & (rx_count == sc.rx_per_step)
        if not valid.all():
            bad = int(np.flatnonzero(~xp.to_numpy(valid))[0])
            raise ValueError(
                f"action of trial {bad} selects {int(tx_count[bad])} TX and {int(rx_count[bad])} RX; "
                f"exactly tx_per_step={sc.tx_per_step} and rx_per_step={sc.rx_per_step} are required "
                "(or make the env with invalid_action='probe-nothing')"
            )

    def advance(self, actions: Any) -> tuple[dict[str, NDArray], NDArray, dict[str, NDArray]]:
        """The step's work on checked actions: the truth, the probed channels, the tracker, the
        bound, the observation, the reward and ``info``. It reads the step from the device
        (``simulation.clock``) and asks the host nothing but what :func:`deferred_checks` defers, so
        :mod:`.device_forms` can replay it as one graph; :meth:`step` keeps the count on the host."""
        xp = self.xp
        tx_mask = xp.astype(actions[:, : self.num_tx], bool)
        rx_mask = xp.astype(actions[:, self.num_tx :], bool)
        sc = self.scenario
        valid = (tx_mask.sum(axis=1) == sc.tx_per_step) & (rx_mask.sum(axis=1) == sc.rx_per_step)
        self.simulation.advance()
        # invalid trials get placeholder channels (the first stations) and are masked out
        tx_index = xp.where(valid[:, None], true_indices(tx_mask, sc.tx_per_step), xp.arange(sc.tx_per_step))
        rx_index = xp.where(valid[:, None], true_indices(rx_mask, sc.rx_per_step), xp.arange(sc.rx_per_step))
        channels = self.simulation.observe(tx_index, rx_index, valid)

        sinr_reward = xp.einsum("k,bkc->b", self.model.weights, channels.sinr) * valid
        sinr = xp.zeros((self.batch_size, self.model.num_targets, self.num_tx, self.num_rx))
        probed = xp.astype(tx_mask[:, :, None] & rx_mask[:, None, :] & valid[:, None, None], np.int8)
        batch = xp.arange(self.batch_size)[:, None, None]
        targets = xp.arange(self.model.num_targets)[None, :, None]
        sinr[batch, targets, channels.tx_index[:, None, :], channels.rx_index[:, None, :]] = channels.sinr
        sinr *= valid[:, None, None, None]

        self._track(channels)
        if self.tracker is not None:
            self._advance_bound(channels)
        self.last_action = actions
        self.last_valid = valid
        self.invalid_steps = self.invalid_steps + ~valid

        info = self._truth_info()
        weights = self.model.channel_weights(self.simulation.mean_sinr())
        info["expected_reward"] = super_arm_value(weights, tx_mask, rx_mask) * valid
        best_tx, best_rx, best_value = best_super_arm(
            weights, sc.tx_per_step, sc.rx_per_step, self.options.oracle_solver
        )
        info["optimal_reward"] = best_value
        info["optimal_action"] = masks_to_actions(best_tx, best_rx)
        info["action_valid"] = valid
        info["reward_sinr"] = sinr_reward
        reward = sinr_reward
        if self.tracker is not None:
            info["position_bound"] = position_bound(self._bound_covariance)
            info["tracker_repairs"] = xp.copy(self.tracker.repairs)
            info["reward_information"] = self._information_gain()
            if self.options.reward == "information":
                reward = info["reward_information"]
        if self.options.measurements:
            info |= self._measurement_info(channels)
        return self._observation(sinr, probed), reward, info

    def state_slots(self) -> list[tuple[Any, str]]:
        """``(object, attribute)`` of every array the step carries to the next: the truth, the
        clock and keys, the tracker, the bound and the action counts (:mod:`.device_forms` passes
        them through a graph and back)."""
        sim = self.simulation
        slots = [(sim, "state"), (sim, "clock"), (sim.streams, "keys")]
        slots += [(self, "last_action"), (self, "last_valid"), (self, "invalid_steps")]
        if self.tracker is not None:
            slots += [(self, "_bound_covariance")]
            names = ("means", "covs", "log_probs", "estimate", "covariance", "prior_covariance", "repairs")
            slots += [(self.tracker, name) for name in names]
        return slots

    def _warn_if_invalid_dominated(self) -> None:
        """Warns once per env when, in an episode just ended, most actions of a trial probed
        nothing: a learner on the raw ``MultiBinary`` action that settled on invalid actions."""
        worst = int(self.invalid_steps.max())
        if self._warned_invalid or 2 * worst <= self.horizon:
            return
        self._warned_invalid = True
        warnings.warn(
            f"{worst} of the episode's {self.horizon} actions selected a number of stations other "
            f"than tx_per_step={self.scenario.tx_per_step} and rx_per_step={self.scenario.rx_per_step} "
            "and probed nothing (reward 0). A learner on the raw MultiBinary action rarely finds the "
            "valid ones: train on the Flat id (MimoRadarSelectFlat-v1, every action a valid super arm), "
            "or make the env with invalid_action='raise' to stop at the first invalid action "
            "(this warning is given once per env)",
            UserWarning,
            stacklevel=5,
        )

    @_in_precision
    def oracle_action(self) -> NDArray[np.int8]:
        """The optimal super arm for the true mean SINR of the coming step, (B, M + N)."""
        upcoming = positions(self.simulation.upcoming_state())
        weights = self.model.channel_weights(self.model.mean_sinr(upcoming))
        tx, rx, _ = best_super_arm(
            weights, self.scenario.tx_per_step, self.scenario.rx_per_step, self.options.oracle_solver
        )
        return masks_to_actions(tx, rx)

    @_in_precision
    def tracking_oracle_action(self, criterion: str = "trace") -> NDArray[np.int8]:
        """The super arm of the coming step that minimises the predicted posterior position
        error (:mod:`~mimo_radar_env.tracking.selection`, for the env's fusion), from the
        tracker's prediction and the channels' true ``lambda``: exact over all super arms up
        to :data:`~mimo_radar_env.tracking.selection.MAX_ENUMERATED_SUPER_ARMS`, greedy over
        stations beyond; (B, M + N)."""
        if self.tracker is None:
            raise RuntimeError("the tracking oracle needs the tracker: make the env with tracking=True")
        sc = self.scenario
        upcoming = positions(self.simulation.upcoming_state())
        variance = self.model.measurement_variance(self.simulation.quality(self.model.mean_sinr(upcoming)))
        predicted = self.tracker.predicted_state()
        position_cov = self._predicted_position_covariance()
        info = channel_information(positions(predicted), self.model.tx, self.model.rx, variance)
        tx, rx = select_for_tracking(
            position_cov, info, sc.weights, sc.tx_per_step, sc.rx_per_step, criterion, self.options.fusion
        )
        return masks_to_actions(tx, rx)

    def tracking_forecast(self, horizon: int) -> Forecast:
        """What a receding-horizon tracking oracle scores plans of the next ``horizon`` steps on
        (:class:`~mimo_radar_env.tracking.planning.Forecast`): the tracker's predicted covariance,
        and each channel's position information at step ``t + h`` at the tracker's prediction
        carried by the constant-velocity model, with the channel's true ``lambda`` along the
        truth (reads the truth: oracle only). Its first step is best-tracking's."""
        if self.tracker is None:
            raise RuntimeError("the tracking oracle needs the tracker: make the env with tracking=True")
        self._numpy_only("the tracking forecast")
        if isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 1:
            raise ValueError(f"horizon must be an integer >= 1, got {horizon!r}")
        truth = positions(self.simulation.future_states(horizon))  # (B, H, K, 2)
        variance = self.model.measurement_variance(self.simulation.quality(self.model.mean_sinr(truth)))
        F = transition_matrix(0.0, self.scenario.sample_time)
        predicted = [self.tracker.predicted_state()]
        for _ in range(1, horizon):
            predicted.append(predicted[-1] @ F.T)
        planned = positions(np.stack(predicted, axis=1))
        return Forecast(
            covariance=self.tracker.predicted_covariance(),
            information=channel_information(planned, self.model.tx, self.model.rx, variance),
            transition=F,
            process_cov=self.model.process_cov,
            weights=np.asarray(self.scenario.weights, dtype=np.float64),
        )

    def bound_forecast(self) -> Forecast:
        """The rest of the episode as the PCRB sees it, for the offline bound on selection
        (:func:`~mimo_radar_env.tracking.planning.best_achievable_bound`): the bound's prior of
        the coming step, every channel's information at the true positions of each remaining
        step with its true variances, and each target's true motion after each step (reads the
        truth)."""
        if self.tracker is None:
            raise RuntimeError("the bound needs the tracker: make the env with tracking=True")
        self._numpy_only("the bound's forecast")
        horizon = self.horizon - self.step_index
        if horizon < 1:
            raise RuntimeError(f"the episode ended after {self.horizon} steps; call reset()")
        truth = positions(self.simulation.future_states(horizon))
        variance = self.model.measurement_variance(self.simulation.quality(self.model.mean_sinr(truth)))
        transitions = np.moveaxis(self.model.transitions, 1, 0)  # (T, K, 4, 4): step t -> t + 1
        F = transitions[self.step_index]
        prior = F @ self._bound_covariance @ np.swapaxes(F, -1, -2) + self.model.process_cov
        after = transitions[self.step_index + 1 : self.step_index + horizon]
        # the motion after the last step is never used; the last one stands in for it
        after = np.concatenate([after, transitions[-1:]])
        return Forecast(
            covariance=prior,
            information=channel_information(truth, self.model.tx, self.model.rx, variance),
            transition=after,
            process_cov=self.model.process_cov,
            weights=np.asarray(self.scenario.weights, dtype=np.float64),
        )

    # ----------------------------------------------------------- helpers
    def _numpy_only(self, what: str) -> None:
        if self.xp.is_torch:
            raise NotImplementedError(
                f"{what} runs on numpy only: make the env with device=None (this one has "
                f"device={str(self.device)!r})"
            )

    def _advance_bound(self, channels: ChannelObservations) -> None:
        """The PCRB of the step: the true motion, then the probed channels at the true
        positions with their true covariances (docs/model.md, section 14)."""
        truth = self.simulation.positions[:, :, None, :]  # the truth of this step, (B, K, 1, 2)
        tx = self.model.tx[channels.tx_index][:, None]  # (B, 1, C, 2)
        rx = self.model.rx[channels.rx_index][:, None]
        jac = channel_jacobian(truth, tx, rx)  # (B, K, C, 2, 2)
        per_channel = jacobian_information(jac, channels.noise_variance)  # the true Sigma0 / lambda
        measured = per_channel.sum(axis=2) * channels.valid[:, None, None, None]
        transition = self.model.transition_at(self.simulation.clock - 1)  # (K, 4, 4): step t-1 -> t
        process_cov = self.model.process_cov
        self._bound_covariance = bound_step(self._bound_covariance, transition, process_cov, measured)

    def _information_gain(self) -> NDArray[np.float64]:
        """``sum_k Omega_k (log det P_pos,pred - log det P_pos,post)`` of the last step, (B,) nats."""
        assert self.tracker is not None
        xp = self.xp
        before = position_determinant(self.tracker.prior_covariance)
        after = position_determinant(self.tracker.covariance)
        return xp.matmul(xp.log(before / after), self.model.weights)

    def _tracker_variance(self, channels: ChannelObservations) -> NDArray:
        """The measurement variances (B, K, C, 2) the tracker uses, per ``filter_noise``."""
        if self.options.filter_noise == "true":
            return channels.noise_variance
        lam_hat = self.model.quality(channels.sinr, target_axis=1, scale=self.options.lambda_scale)
        return self.model.measurement_variance(lam_hat)

    def _track(self, channels: ChannelObservations) -> None:
        if self.tracker is None:
            return
        self.tracker.step(
            self.model.tx[channels.tx_stations],
            self.model.rx[channels.rx_stations],
            channels.measurement,
            self._tracker_variance(channels),
            channels.valid,
        )

    def _measurement_info(self, channels: ChannelObservations) -> dict[str, NDArray]:
        xp = self.xp
        invalid = ~channels.valid[:, None, None, None]
        variance = self._tracker_variance(channels)
        covariance = variance[..., :, None] * xp.eye(2)  # (B, K, C, 2, 2), diagonal
        return {
            "measurement": xp.where(invalid, xp.nan, channels.measurement),
            "measurement_covariance": xp.where(invalid[..., None], xp.nan, covariance),
            "measurement_tx": xp.copy(channels.tx_index),
            "measurement_rx": xp.copy(channels.rx_index),
        }

    def _observation(self, sinr: NDArray, probed: NDArray) -> dict[str, NDArray]:
        obs = {"sinr": sinr, "probed": probed}
        tracker = self.tracker
        if tracker is None:
            return obs
        obs |= {
            "track": self.xp.copy(tracker.estimate),
            "track_pred": tracker.predicted_state(),
            "track_pos_cov": position_block(tracker.covariance),
            "mode_prob": tracker.model_probabilities,
        }
        if self.options.prediction_covariance:
            predicted = tracker.predicted_covariance()
            obs["track_pred_pos_cov"] = position_block(predicted)
            obs["track_pred_cov"] = predicted
        return obs

    def _predicted_position_covariance(self) -> NDArray[np.float64]:
        """The position block of the tracker's predicted mixture covariance, (B, K, 2, 2)."""
        assert self.tracker is not None
        return position_block(self.tracker.predicted_covariance())

    def _truth_info(self) -> dict[str, NDArray]:
        state = self.simulation.state
        xp = self.xp
        info = {"mean_sinr": self.simulation.mean_sinr(), "true_state": xp.copy(state)}
        if self.tracker is not None:
            info["position_error"] = xp.linalg.norm(
                self.tracker.estimate[..., POSITION] - state[..., POSITION], axis=-1
            )
        return info
