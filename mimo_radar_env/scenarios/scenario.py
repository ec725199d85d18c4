"""The scenario: the radar layout, the targets and every model constant, as validated data.

A :class:`Scenario` is plain data. Every field is checked when the scenario is built;
a bad field raises :class:`ScenarioError` naming the field and what is allowed.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core.motion import POSITION, nominal_trajectories, positions, transition_matrix
from . import validation as check
from .validation import ScenarioError

#: Set while :meth:`Scenario._validated` builds a scenario from fields it has just checked.
_CHECKED: ContextVar[bool] = ContextVar("_CHECKED", default=False)

#: Longest episode a scenario may ask for (steps): the model keeps per-step arrays.
MAX_HORIZON = 1_000_000
#: Every noise-free track must stay this far (m) from every station.
MIN_STATION_DISTANCE = 10.0
#: Positions and velocities of a noise-free track stay below this (m, m/s): squares stay finite.
MAX_COORDINATE = 1e12
#: Stations and initial target positions lie within this distance of the origin (m).
MAX_POSITION = 1e8
#: The most transmitters, and the most receivers, of a scenario.
MAX_STATIONS = 1000
#: The physical ranges of the noise and uncertainty fields (docs/model.md, section 1): a standard
#: deviation from 1 mm (1 mm/s) up to the scene's extent, an azimuth error from 1 microradian up
#: to pi. Beyond them the model means nothing and the tracker's arithmetic breaks down.
MIN_METRE_VARIANCE = 1e-6  # m^2 (and (m/s)^2 for velocities)
MIN_AZIMUTH_VARIANCE = 1e-12  # rad^2
MAX_AZIMUTH_VARIANCE = float(np.pi**2)
MIN_SAMPLE_TIME = 1e-3  # s
MAX_SAMPLE_TIME = 1e6  # s
#: The largest ratio of an initial covariance's eigenvalues.
MAX_CONDITION = 1e12


@dataclass(frozen=True)
class Maneuver:
    """A coordinated turn: NCT with ``turn_rate_deg`` (deg/s) for ``start <= t < stop``.

    Positive turn rates turn counter-clockwise.
    """

    turn_rate_deg: float
    start: int
    stop: int


@dataclass(frozen=True)
class Target:
    """One point target: its initial estimate, covariance and maneuver schedule.

    The true initial state of each trial is drawn from
    ``N(initial_state, initial_covariance)``; the tracker starts at
    ``initial_state``, ``initial_covariance``.
    """

    initial_state: NDArray[np.float64]  # [x, vx, y, vy] in m, m/s
    initial_covariance: NDArray[np.float64]  # (4, 4)
    maneuvers: tuple[Maneuver, ...] = ()

    def __eq__(self, other: object) -> bool:
        return NotImplemented if type(other) is not type(self) else not field_differences(self, other)


def field_differences(a: Any, b: Any) -> list[str]:
    """The fields in which two dataclasses of one type differ, arrays compared by value (the
    generated ``__eq__`` compares them with ``==`` and raises on the result's truth value)."""

    def equal(x: Any, y: Any) -> bool:
        return np.array_equal(x, y) if isinstance(x, np.ndarray) or isinstance(y, np.ndarray) else x == y

    return [f.name for f in dataclasses.fields(a) if not equal(getattr(a, f.name), getattr(b, f.name))]


_TARGET_KEYS = {"initial_state", "initial_covariance", "maneuvers"}
_MANEUVER_KEYS = {"turn_rate_deg", "start", "stop"}


@dataclass(frozen=True)
class Scenario:
    """A distributed MIMO radar scenario (docs/model.md).

    Attributes
    ----------
    name : str
        Label used in reports, and the folder a study writes the scenario's run into: 1 to 100
        letters, digits, ``_``, ``-``, ``+`` or ``.`` (not first). Without one, ``from_dict`` names
        the scenario ``"custom"`` and ``load_scenario`` after its file (other characters as ``-``).
    tx_positions, rx_positions : arrays (M, 2), (N, 2)
        Station coordinates in metres.
    tx_per_step, rx_per_step : int
        ``Ms`` and ``Ns``: how many transmitters and receivers are used each step.
    targets : tuple of Target
        The K targets.
    weights : array (K,)
        Target weights ``Omega`` of eq17/eq34 (non-negative, not all zero).
    horizon : int
        ``T``, the number of steps of an episode.
    sample_time : float
        ``Ts`` in seconds.
    process_noise : float
        ``Qs``, the acceleration noise variance (m^2/s^4) of eq1/eq3.
    tx_power : array (M,)
        ``P_m`` in watts.
    noise_power : float
        ``sigma_noise^2``.
    interference_power : array (N,)
        ``sigma_int_n^2`` per receiver.
    rcs : array (K, M, N)
        ``psi`` of eq5 per target and channel.
    range_variance, azimuth_variance : float
        ``Sigma0 = diag(range_variance, azimuth_variance)`` (m^2, rad^2) of eq32.
    peak_sinr : float
        ``S_max`` of eq32: the per-scenario constant ``C`` puts the largest
        noise-free mean SINR at this value (linear; 10 = 10 dB).
    truth_seed : int
        Seed of the one true trajectory every trial shares when the env runs with
        ``truth="shared"`` (reading 1).
    """

    name: str
    tx_positions: NDArray[np.float64]
    rx_positions: NDArray[np.float64]
    tx_per_step: int
    rx_per_step: int
    targets: tuple[Target, ...]
    weights: NDArray[np.float64]
    horizon: int = 1000
    sample_time: float = 1.0
    process_noise: float = 0.1
    tx_power: NDArray[np.float64] = field(default_factory=lambda: np.array(1000.0))
    noise_power: float = 1e-26
    interference_power: NDArray[np.float64] = field(default_factory=lambda: np.array(0.5e-21))
    rcs: NDArray[np.float64] = field(default_factory=lambda: np.array(1.0))
    range_variance: float = 5.0
    azimuth_variance: float = 0.002
    peak_sinr: float = 10.0
    truth_seed: int = 0

    def __post_init__(self) -> None:
        # A scenario built directly (``Scenario(...)``, ``dataclasses.replace``) is checked as
        # ``from_dict`` checks one, and holds the fields it would hold.
        if _CHECKED.get():
            return
        checked = Scenario.from_dict(self.to_dict())
        for f in dataclasses.fields(self):
            object.__setattr__(self, f.name, getattr(checked, f.name))

    def __eq__(self, other: object) -> bool:
        return NotImplemented if type(other) is not type(self) else not field_differences(self, other)

    # ------------------------------------------------------------------ sizes
    @property
    def num_tx(self) -> int:
        return self.tx_positions.shape[0]

    @property
    def num_rx(self) -> int:
        return self.rx_positions.shape[0]

    @property
    def num_targets(self) -> int:
        return len(self.targets)

    @property
    def num_channels_per_step(self) -> int:
        return self.tx_per_step * self.rx_per_step

    @property
    def measurement_covariance(self) -> NDArray[np.float64]:
        """``Sigma0`` of eq32."""
        return np.diag([self.range_variance, self.azimuth_variance])

    # --------------------------------------------------------- construction
    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scenario:
        """Build and validate a scenario from plain data (as read from YAML/TOML)."""
        data = dict(data)
        allowed = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - allowed)
        if unknown:
            raise ScenarioError(f"unknown scenario key(s) {unknown}; allowed keys are {sorted(allowed)}")
        missing = sorted(
            f.name
            for f in dataclasses.fields(cls)
            if f.default is dataclasses.MISSING
            and f.default_factory is dataclasses.MISSING
            and f.name not in data
        )
        # weights default to equal weights; name defaults to "custom"
        missing = [m for m in missing if m not in {"weights", "name"}]
        if missing:
            raise ScenarioError(f"scenario is missing required key(s) {missing}")
        data.setdefault("name", "custom")
        targets = data.get("targets")
        if not isinstance(targets, list | tuple) or len(targets) == 0:
            raise ScenarioError("targets must be a non-empty list of target tables")
        data["targets"] = tuple(parse_target(i, t) for i, t in enumerate(targets))
        if "weights" not in data:
            data["weights"] = [1.0 / len(targets)] * len(targets) if len(targets) > 1 else [1.0]
        return cls._validated(data)

    @classmethod
    def _validated(cls, data: dict[str, Any]) -> Scenario:
        out: dict[str, Any] = {"name": check.scenario_name(data["name"]), "targets": data["targets"]}
        out["tx_positions"] = check.positions("tx_positions", data["tx_positions"])
        out["rx_positions"] = check.positions("rx_positions", data["rx_positions"])
        for name in ("tx_positions", "rx_positions"):
            if len(out[name]) > MAX_STATIONS:
                raise ScenarioError(f"{name} may hold at most {MAX_STATIONS} stations, got {len(out[name])}")
            far = np.abs(out[name]).max()
            if far > MAX_POSITION:
                raise ScenarioError(f"{name} must lie within {MAX_POSITION:g} m of the origin, got {far:g} m")
        num_tx, num_rx = out["tx_positions"].shape[0], out["rx_positions"].shape[0]
        num_targets = len(out["targets"])
        out["tx_per_step"] = check.integer_in(
            "tx_per_step", data["tx_per_step"], 1, num_tx, "M (the number of transmitters)"
        )
        out["rx_per_step"] = check.integer_in(
            "rx_per_step", data["rx_per_step"], 1, num_rx, "N (the number of receivers)"
        )
        defaults = {f.name: f for f in dataclasses.fields(cls)}

        def get(name: str) -> Any:
            if name in data:
                return data[name]
            f = defaults[name]
            return f.default_factory() if f.default_factory is not dataclasses.MISSING else f.default

        out["horizon"] = check.integer_in(
            "horizon", get("horizon"), 1, MAX_HORIZON, "a number of steps; longer episodes are refused"
        )
        for name in ("sample_time", "noise_power", "range_variance", "azimuth_variance", "peak_sinr"):
            out[name] = check.positive_number(name, get(name))
        out["truth_seed"] = check.integer_in("truth_seed", get("truth_seed"), 0, 2**63 - 1, "a seed")
        out["process_noise"] = check.number(name := "process_noise", get(name))
        if out["process_noise"] < 0:
            raise ScenarioError(f"process_noise must be >= 0, got {out['process_noise']}")
        out["tx_power"] = check.positive_array("tx_power", get("tx_power"), (num_tx,))
        out["interference_power"] = check.nonnegative_array(
            "interference_power", get("interference_power"), (num_rx,)
        )
        out["rcs"] = check.positive_array("rcs", get("rcs"), (num_targets, num_tx, num_rx))
        weights = check.numeric_array("weights", get("weights"))
        if weights.shape != (num_targets,):
            raise ScenarioError(
                f"weights must hold one value per target ({num_targets}), got shape {weights.shape}"
            )
        if np.any(weights < 0) or not np.any(weights > 0):
            raise ScenarioError(f"weights must be >= 0 and not all zero, got {weights.tolist()}")
        out["weights"] = weights
        check.distinct_positions("tx_positions", out["tx_positions"])
        check.distinct_positions("rx_positions", out["rx_positions"])
        stations = np.concatenate([out["tx_positions"], out["rx_positions"]])
        for k, target in enumerate(out["targets"]):
            position = target.initial_state[POSITION]
            if np.any(np.all(np.isclose(stations, position, rtol=0, atol=1e-6), axis=1)):
                raise ScenarioError(
                    f"targets[{k}].initial_state puts the target on a station at {position.tolist()} m; "
                    "ranges would be zero and the SINR infinite. Move the target or the station."
                )
            for j, man in enumerate(target.maneuvers):
                if not (0 <= man.start < man.stop <= out["horizon"]):
                    raise ScenarioError(
                        f"targets[{k}].maneuvers[{j}] window [{man.start}, {man.stop}) must lie in "
                        f"[0, horizon={out['horizon']}) with start < stop"
                    )
            windows = sorted((m.start, m.stop) for m in target.maneuvers)
            for (a0, a1), (b0, _) in zip(windows, windows[1:], strict=False):
                if b0 < a1:
                    raise ScenarioError(
                        f"targets[{k}].maneuvers overlap: [{a0}, {a1}) and one starting at {b0}"
                    )
        token = _CHECKED.set(True)
        try:
            scenario = cls(**out)
        finally:
            _CHECKED.reset(token)
        scenario._check_ranges()
        scenario._check_tracks()
        return scenario

    @property
    def extent(self) -> float:
        """The scene's size (m): the largest distance between two of its stations and initial
        target positions, at least 1 km. It bounds the noise and uncertainty fields."""
        points = np.concatenate(
            [self.tx_positions, self.rx_positions, [t.initial_state[POSITION] for t in self.targets]]
        )
        spread = np.linalg.norm(points[:, None] - points[None], axis=-1).max()
        return float(max(spread, 1e3))

    def measurement_quality_range(self) -> tuple[float, float]:
        """The values of a constant ``lambda`` (the env's ``measurement_quality``) that keep both
        measurement variances ``Sigma0 / lambda`` within their physical ranges."""
        low = max(self.range_variance / self.extent**2, self.azimuth_variance / MAX_AZIMUTH_VARIANCE)
        high = min(self.range_variance / MIN_METRE_VARIANCE, self.azimuth_variance / MIN_AZIMUTH_VARIANCE)
        return low, high

    def _check_ranges(self) -> None:
        """The noise and uncertainty fields within their physical ranges (tied to the scene's
        extent and the sample time), each refusal naming the range allowed."""
        extent, step = self.extent, self.sample_time
        if not MIN_SAMPLE_TIME <= step <= MAX_SAMPLE_TIME:
            raise ScenarioError(
                f"sample_time must be in [{MIN_SAMPLE_TIME:g}, {MAX_SAMPLE_TIME:g}] (s), got {step:g}"
            )
        bounds = {
            "range_variance": (
                MIN_METRE_VARIANCE,
                extent**2,
                "m^2: from 1 mm^2 to the scene's extent squared",
            ),
            "azimuth_variance": (MIN_AZIMUTH_VARIANCE, MAX_AZIMUTH_VARIANCE, "rad^2: from 1 urad^2 to pi^2"),
            "process_noise": (
                0.0,
                3 * extent**2 / step**3,
                "m^2/s^3: at most a growth of the scene's extent squared in one step",
            ),
        }
        for name, (low, high, unit) in bounds.items():
            value = getattr(self, name)
            if not low <= value <= high:
                raise ScenarioError(f"{name} must be in [{low:.3g}, {high:.3g}] ({unit}), got {value:g}")
        for k, target in enumerate(self.targets):
            where = f"targets[{k}]"
            position = np.abs(target.initial_state[POSITION]).max()
            if position > MAX_POSITION:
                raise ScenarioError(
                    f"{where}.initial_state must lie within {MAX_POSITION:g} m of the origin, "
                    f"got {position:g} m"
                )
            speed = float(np.linalg.norm(target.initial_state[[1, 3]]))
            if speed * step > extent:
                raise ScenarioError(
                    f"{where} moves {speed * step:.3g} m in one sample_time of {step:g} s, more than the "
                    f"scene's extent of {extent:.3g} m: shorten sample_time or slow the target"
                )
            variances = np.linalg.eigvalsh(target.initial_covariance)
            upper = max(extent, extent / step) ** 2
            if variances.max() > MAX_CONDITION * variances.min():
                raise ScenarioError(
                    f"{where}.initial_covariance has eigenvalues from {variances.min():.3g} to "
                    f"{variances.max():.3g}: a condition number above {MAX_CONDITION:g}, beyond what the "
                    "tracker's arithmetic resolves"
                )
            if variances.min() < MIN_METRE_VARIANCE or variances.max() > upper:
                raise ScenarioError(
                    f"{where}.initial_covariance must have eigenvalues in "
                    f"[{MIN_METRE_VARIANCE:g}, {upper:.3g}] "
                    f"(m^2 and (m/s)^2: from 1 mm to the scene's extent per sample time), got "
                    f"[{variances.min():.3g}, {variances.max():.3g}]"
                )

    def _check_tracks(self) -> None:
        """The noise-free tracks stay finite and at least ``MIN_STATION_DISTANCE`` from every station."""
        rates = turn_rate_schedule(self)
        with np.errstate(over="ignore", invalid="ignore"):
            nominal = nominal_trajectories(
                np.stack([t.initial_state for t in self.targets]), transition_matrix(rates, self.sample_time)
            )
        with np.errstate(invalid="ignore"):
            bad = ~(np.abs(nominal) < MAX_COORDINATE).all(axis=(1, 2))
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ScenarioError(
                f"targets[{k}]'s noise-free track leaves the finite numbers (|x| < {MAX_COORDINATE:g} m and "
                "m/s) within the horizon: check its initial_state, sample_time and horizon"
            )
        stations = np.concatenate([self.tx_positions, self.rx_positions])
        names = [f"TX{m + 1}" for m in range(self.num_tx)] + [f"RX{n + 1}" for n in range(self.num_rx)]
        for k in range(self.num_targets):
            distance, step, station = closest_approach(positions(nominal[k]), stations)
            if distance < MIN_STATION_DISTANCE:
                raise ScenarioError(
                    f"targets[{k}]'s noise-free track passes {distance:.3g} m from {names[station]} "
                    f"(between steps {step} and {step + 1}); every track must stay at least "
                    f"{MIN_STATION_DISTANCE:g} m from every station (the SINR grows as range^-4)"
                )

    def replace(self, **overrides: Any) -> Scenario:
        """A copy with some fields replaced, validated again."""
        data = self.to_dict()
        data.update(overrides)
        return Scenario.from_dict(data)

    def to_dict(self) -> dict[str, Any]:
        """Plain, serialisable data (lists and numbers); ``from_dict`` inverts it."""
        return {
            "name": self.name,
            "tx_positions": _plain(self.tx_positions),
            "rx_positions": _plain(self.rx_positions),
            "tx_per_step": self.tx_per_step,
            "rx_per_step": self.rx_per_step,
            "targets": [_plain(t) for t in self.targets]
            if isinstance(self.targets, list | tuple)
            else self.targets,
            "weights": _plain(self.weights),
            "horizon": self.horizon,
            "sample_time": self.sample_time,
            "process_noise": self.process_noise,
            "tx_power": _plain(self.tx_power),
            "noise_power": self.noise_power,
            "interference_power": _plain(self.interference_power),
            "rcs": _plain(self.rcs),
            "range_variance": self.range_variance,
            "azimuth_variance": self.azimuth_variance,
            "peak_sinr": self.peak_sinr,
            "truth_seed": self.truth_seed,
        }


def _plain(value: Any) -> Any:
    """``value`` as plain data for ``from_dict``: arrays as lists, targets and maneuvers as tables;
    anything else as it is (``from_dict`` names what it cannot take)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Target):
        maneuvers = value.maneuvers
        return {
            "initial_state": _plain(value.initial_state),
            "initial_covariance": _plain(value.initial_covariance),
            "maneuvers": [_plain(m) for m in maneuvers] if isinstance(maneuvers, list | tuple) else maneuvers,
        }
    if isinstance(value, Maneuver):
        return dataclasses.asdict(value)
    return value


def parse_target(index: int, raw: Any) -> Target:
    where = f"targets[{index}]"
    raw = _plain(raw)  # a Target built directly is checked as its table would be
    if not isinstance(raw, Mapping):
        raise ScenarioError(f"{where} must be a table with keys {sorted(_TARGET_KEYS)}")
    unknown = sorted(set(raw) - _TARGET_KEYS)
    if unknown:
        raise ScenarioError(f"unknown key(s) {unknown} in {where}; allowed: {sorted(_TARGET_KEYS)}")
    if "initial_state" not in raw:
        raise ScenarioError(f"{where}.initial_state is required ([x, vx, y, vy] in m and m/s)")
    state = check.numeric_array(f"{where}.initial_state", raw["initial_state"])
    if state.shape != (4,):
        raise ScenarioError(f"{where}.initial_state must be [x, vx, y, vy], got shape {state.shape}")
    cov = check.numeric_array(f"{where}.initial_covariance", raw.get("initial_covariance", [20.0] * 4))
    if cov.shape == (4,):
        cov = np.diag(cov)
    if cov.shape != (4, 4):
        raise ScenarioError(
            f"{where}.initial_covariance must be 4 variances or a 4x4 matrix, got shape {cov.shape}"
        )
    if not np.allclose(cov, cov.T) or np.any(np.linalg.eigvalsh((cov + cov.T) / 2) <= 0):
        raise ScenarioError(f"{where}.initial_covariance must be symmetric positive definite")
    raw_maneuvers = raw.get("maneuvers", []) or []
    if not isinstance(raw_maneuvers, list | tuple):
        raise ScenarioError(f"{where}.maneuvers must be a list of maneuver tables, got {raw_maneuvers!r}")
    maneuvers = []
    for j, man in enumerate(raw_maneuvers):
        mwhere = f"{where}.maneuvers[{j}]"
        man = _plain(man)
        if not isinstance(man, Mapping) or set(man) != _MANEUVER_KEYS:
            raise ScenarioError(f"{mwhere} must be a table with exactly the keys {sorted(_MANEUVER_KEYS)}")
        rate = check.number(f"{mwhere}.turn_rate_deg", man["turn_rate_deg"])
        if rate == 0:
            raise ScenarioError(f"{mwhere}.turn_rate_deg must be non-zero (NCV needs no maneuver entry)")
        maneuvers.append(
            Maneuver(
                rate,
                check.integer_in(f"{mwhere}.start", man["start"], 0, None, "a step index >= 0"),
                check.integer_in(f"{mwhere}.stop", man["stop"], 1, None, "a step index >= 1"),
            )
        )
    return Target(state, cov, tuple(maneuvers))


def closest_approach(
    track: NDArray[np.float64], stations: NDArray[np.float64], chunk: int = 100_000
) -> tuple[float, int, int]:
    """Smallest distance from the segments of ``track`` (T+1, 2) to ``stations`` (S, 2).

    Returns the distance, the step at the start of the closest segment and the station's index.
    """
    best = (np.inf, 0, 0)
    if len(track) == 1:
        track = np.concatenate([track, track])
    for start in range(0, len(track) - 1, chunk):
        a = track[start : start + chunk][:, None, :]  # (c, 1, 2)
        b = track[start + 1 : start + chunk + 1][:, None, :]
        a = a[: len(b)]
        ab = b - a
        length2 = np.einsum("tsi,tsi->ts", ab, ab)
        along = np.einsum("tsi,tsi->ts", stations[None] - a, ab) / np.where(length2 > 0, length2, 1.0)
        closest = a + np.clip(along, 0.0, 1.0)[..., None] * ab
        distance = np.linalg.norm(closest - stations[None], axis=-1)  # (c, S)
        step, station = np.unravel_index(np.argmin(distance), distance.shape)
        if distance[step, station] < best[0]:
            best = (float(distance[step, station]), int(start + step), int(station))
    return best


def turn_rate_schedule(scenario: Scenario) -> NDArray[np.float64]:
    """Turn rate (rad/s) of the transition ``t -> t+1`` for each target: shape (K, T)."""
    rates = np.zeros((scenario.num_targets, scenario.horizon))
    for k, target in enumerate(scenario.targets):
        for man in target.maneuvers:
            rates[k, man.start : man.stop] = math.radians(man.turn_rate_deg)
    return rates
