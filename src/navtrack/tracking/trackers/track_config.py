"""Tracker parameters (:class:`TrackerConfig`), what the stages derive from them
(:class:`TrackerModel`), and the codes of a detection's fate and of a track's end."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import Literal

import numpy as np

from navtrack._typing import FloatArray
from navtrack.tracking.gating import chi2_threshold
from navtrack.tracking.jpda import JpdaConfig
from navtrack.tracking.models import (
    LinearMotion,
    MeasurementModel,
    constant_velocity,
    linear_position,
)

__all__ = [
    "DET_STATUS_NAMES",
    "TRACK_END_NAMES",
    "DetStatus",
    "TrackEnd",
    "TrackerConfig",
    "TrackerModel",
]


class DetStatus(IntEnum):
    """Fate of a detection (``TrackerResult.det_status``; names as the CLI prints them)."""

    CONFIRMED = 0  # updated a confirmed track
    TENTATIVE = 1  # updated a tentative track
    STARTED = 2  # started a track (one-point, or either point of a two-point initiation)
    SEED = 3  # kept as a seed for initiation (never paired)
    UNUSED = 4  # inside a gate but not associated (GNN loser / JPDA low probability)


DET_STATUS_NAMES = tuple(s.name.lower() for s in DetStatus)


class TrackEnd(IntEnum):
    """Why a track ended (``TrackerResult.end_reason``; names as written in the track table)."""

    COAST = 0  # no update for longer than ``max_coast_s``
    COVARIANCE = 1  # position standard deviation above ``max_position_std_m``
    UNCONFIRMED = 2  # tentative, not confirmed within ``confirm_window_s``
    END_OF_DATA = 3  # alive after the last detection


TRACK_END_NAMES = tuple(s.name.lower() for s in TrackEnd)


@dataclass(frozen=True, slots=True)
class TrackerConfig:
    """Tracker parameters (SI units).

    ``init_from``: which detections may start tracks: those inside no track's gate, or all
    that were not associated (GNN: unassigned; JPDA: summed association probability < 0.5).

    ``imm_q``: process-noise levels of an IMM of motion models sharing ``motion``'s form (e.g.
    ``(1e-5, 1e-2)`` for moored and manoeuvring ships); ``None`` = a single model with
    ``motion.q``. ``imm_sojourn_s``: mean time spent in a model; over a step ``dt`` the model is
    left with probability ``1 - exp(-dt / imm_sojourn_s)`` (a continuous-time Markov chain, so
    irregular report times switch models at the same rate as regular scans).

    ``scan_window_s``: reports at distinct times within this span are processed as one scan
    (:func:`scan_windows`); 0 = one scan per distinct time.

    ``gnn_density_at_gate``: GNN only. False: one competing-report density
    ``clutter_density`` for every track. True: each track's own, the density at which a
    report on the edge of its gate ties a missed detection (:func:`gate_edge_log_density`,
    from the track's predicted innovation covariance), so that every report inside a gate
    is worth assigning; one λ from σ alone keeps a report only well inside the gate of a
    track whose prediction is uncertain (NIS below 3.7 against a gate at 18.4 for 10 s
    ADS-B reports), and the reports it leaves start duplicate tracks.

    ``continue_tracks``: a newly confirmed track that continues a confirmed track ended by
    coasting or covariance takes the ended track's id
    (:func:`~navtrack.tracking.trackers.management.continuation`): a target unreported for
    longer than its track can coast keeps its identity when it is reported again.

    The defaults suit ships (AIS); :meth:`for_aircraft` gives ADS-B values.
    """

    motion: LinearMotion = field(default_factory=lambda: constant_velocity(2, 0.05, "continuous"))
    sigma_m: float = 25.0
    associator: Literal["gnn", "jpda"] = "gnn"
    pd: float = 0.9
    clutter_density: float = 1e-9
    gate_probability: float = 0.9999
    init_max_speed_mps: float = 30.0
    init_max_dt_s: float = 400.0
    confirm_hits: int = 3
    confirm_window_s: float = 900.0
    max_coast_s: float = 600.0
    max_position_std_m: float = 2000.0
    max_exact_bits: int = 20
    k_best: int = 1000
    pregate_pairs: int = 4000
    init_from: Literal["outside_gates", "unassociated"] = "outside_gates"
    init_velocity_std_mps: float = 1.0
    imm_q: tuple[float, ...] | None = None
    imm_sojourn_s: float = 300.0
    scan_window_s: float = 0.0
    gnn_density_at_gate: bool = False
    continue_tracks: bool = False

    def __post_init__(self) -> None:
        if self.motion.ndim != 2:
            raise ValueError("the tracker works on 2-D (east, north) positions: motion.ndim = 2")
        if self.init_from not in ("outside_gates", "unassociated"):
            raise ValueError(
                f"init_from must be 'outside_gates' or 'unassociated', got {self.init_from!r}"
            )
        if self.associator not in ("gnn", "jpda"):
            raise ValueError(f"associator must be 'gnn' or 'jpda', got {self.associator!r}")
        for name in (
            "sigma_m",
            "clutter_density",
            "init_max_speed_mps",
            "init_max_dt_s",
            "init_velocity_std_mps",
            "confirm_window_s",
            "max_coast_s",
            "max_position_std_m",
        ):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not 0 < self.pd < 1:
            raise ValueError(f"pd must be in (0, 1), got {self.pd}")
        if self.imm_q is not None and (len(self.imm_q) < 2 or min(self.imm_q) < 0):
            raise ValueError(f"imm_q must hold >= 2 values >= 0, got {self.imm_q}")
        if not (np.isfinite(self.imm_sojourn_s) and self.imm_sojourn_s > 0):
            raise ValueError(f"imm_sojourn_s must be finite and > 0, got {self.imm_sojourn_s}")
        if not (np.isfinite(self.scan_window_s) and self.scan_window_s >= 0):
            raise ValueError(f"scan_window_s must be finite and >= 0, got {self.scan_window_s}")
        if self.confirm_hits < 2:
            raise ValueError(f"confirm_hits must be >= 2, got {self.confirm_hits}")

    @staticmethod
    def for_ships(associator: Literal["gnn", "jpda"] = "gnn") -> TrackerConfig:
        """AIS ships: IMM of moored (q = 1e-5 m²/s³) and manoeuvring (1e-2) CV models,
        σ = 25 m, λ = 1e-6 /m² (harbours: other ships rather than clutter compete for a
        report), tracks started from unassociated reports, 3 updates within 15 min to confirm,
        coast 10 min. Values tuned on the Solent file (moored ships report every 3 min, moving
        ones every 2-10 s)."""
        return TrackerConfig(
            associator=associator,
            imm_q=(1e-5, 1e-2),
            confirm_hits=3,
            clutter_density=1e-6,
            init_from="unassociated",
        )

    @staticmethod
    def for_aircraft(associator: Literal["gnn", "jpda"] = "gnn") -> TrackerConfig:
        """Aircraft at 10 s reports: q = 300 m²/s³ (turns at a few m/s²), σ = 50 m, 350 m/s,
        coast 60 s (values tuned on the OpenSky file)."""
        return TrackerConfig(
            motion=constant_velocity(2, 300.0, "continuous"),
            sigma_m=50.0,
            associator=associator,
            pd=0.95,
            clutter_density=1e-10,
            init_max_speed_mps=350.0,
            init_max_dt_s=60.0,
            confirm_hits=3,
            confirm_window_s=60.0,
            max_coast_s=60.0,
            max_position_std_m=5000.0,
        )


@dataclass(frozen=True, slots=True, eq=False)
class TrackerModel:
    """What the stages need, derived once from a :class:`TrackerConfig`.

    Attributes
    ----------
    config : TrackerConfig
    motions : tuple of LinearMotion
        The ``r`` motion models (one, or the IMM's, sharing ``config.motion``'s form).
    measurement : MeasurementModel
        Measurement of the scans (the tracker: east/north position, ``sigma_m`` per axis).
    gamma : float
        Chi-square gate size for ``config.gate_probability`` and the measurement dimension.
    jpda : JpdaConfig
        JPDA parameters (``pd``, ``clutter_density``, ``gate_probability``, ``max_exact_bits``,
        ``k_best`` of the config).
    """

    config: TrackerConfig
    motions: tuple[LinearMotion, ...]
    measurement: MeasurementModel
    gamma: float
    jpda: JpdaConfig

    @property
    def q(self) -> FloatArray:
        """(r,) process-noise level of each motion model."""
        return np.array([m.q for m in self.motions])

    @staticmethod
    def from_config(config: TrackerConfig) -> TrackerModel:
        """Motion models, position measurement, gate size and JPDA parameters of ``config``."""
        mot = config.motion
        qs = (mot.q,) if config.imm_q is None else tuple(config.imm_q)
        meas = linear_position(mot.dim_x, mot.position_index, config.sigma_m)
        return TrackerModel(
            config,
            tuple(LinearMotion(mot.ndim, mot.order, q, mot.noise) for q in qs),
            meas,
            chi2_threshold(config.gate_probability, meas.dim_z),
            JpdaConfig(
                config.pd,
                config.clutter_density,
                config.gate_probability,
                config.max_exact_bits,
                config.k_best,
            ),
        )
