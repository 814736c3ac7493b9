"""Mean pseudorange residuals at a known position, per system and per satellite.

Integrity tests read residuals: a model bias (a group delay left out, a wrong clock reference)
makes them exclude healthy satellites. :func:`residual_bias` evaluates the residuals of an SPP
estimate at the *reference* position (the receiver clocks re-estimated there), so that what
remains is measurement and model error, and averages them per satellite and per system.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray, IntArray
from navtrack.gnss.spp import PositionEstimate, SppStatus

__all__ = ["ResidualBias", "residual_bias"]


@dataclass(frozen=True, slots=True, eq=False)
class ResidualBias:
    """Mean residuals at the reference position.

    Attributes
    ----------
    sats : tuple of str, length S
    sat_mean_m : ndarray, shape (S,)
        Mean residual of each satellite over the epochs it was used (m; NaN if never).
    sat_count : ndarray of int, shape (S,)
    systems : tuple of str
        Systems present.
    system_mean_m : ndarray, shape (len(systems),)
        Mean residual of all measurements of each system (m).
    system_count : ndarray of int, shape (len(systems),)
    """

    sats: tuple[str, ...]
    sat_mean_m: FloatArray
    sat_count: IntArray
    systems: tuple[str, ...]
    system_mean_m: FloatArray
    system_count: IntArray

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def table(self) -> str:
        """The per-system and per-satellite means as printable lines."""
        lines = ["system  mean_m   n"]
        for s, m, n in zip(self.systems, self.system_mean_m, self.system_count, strict=True):
            lines.append(f"{s:<6} {m:+7.3f} {n:5d}")
        lines.append("sat     mean_m   n")
        for s, m, n in zip(self.sats, self.sat_mean_m, self.sat_count, strict=True):
            if n:
                lines.append(f"{s:<6} {m:+7.3f} {n:5d}")
        return "\n".join(lines)


def residual_bias(
    estimate: PositionEstimate, sats: tuple[str, ...], ref_xyz_m: ArrayLike
) -> ResidualBias:
    """Per-satellite and per-system mean residuals at a reference position.

    The residuals ``v`` at the estimate are moved to the reference position with the design
    matrix (``v_ref = v - B_pos (x_ref - x_hat)``, exact to the linearisation, metres for
    errors of metres) and the clock parameters are re-estimated there by weighted least
    squares (per epoch, ``v' = v_ref - B_clk dc``), so that the residuals keep neither the
    position error nor a common clock offset of each clock group.

    Parameters
    ----------
    estimate : PositionEstimate
        Of the epochs to average (only epochs with ``status == ok`` count).
    sats : tuple of str, length S
        Satellite ids of the satellite axis (``Measurements.sats``).
    ref_xyz_m : array_like, shape (3,) or (B, 3)
        Reference position (ECEF, m).

    Returns
    -------
    ResidualBias
    """
    ref = np.broadcast_to(np.asarray(ref_xyz_m, dtype=float), estimate.x[:, :3].shape)
    ok = estimate.status == SppStatus.OK
    used = estimate.used & ok[:, None] & (estimate.weights > 0)
    b = estimate.design
    v = np.nan_to_num(estimate.residuals_m) - np.einsum(
        "bsp,bp->bs", b[..., :3], ref - estimate.x[:, :3]
    )
    w = np.where(used, estimate.weights, 0.0)
    bc = b[..., 3:]
    n = np.einsum("bsp,bs,bsq->bpq", bc, w, bc)
    rhs = np.einsum("bsp,bs,bs->bp", bc, w, v)
    dc = (np.linalg.pinv(n) @ rhs[..., None])[..., 0]
    v = np.where(used, v - np.einsum("bsp,bp->bs", bc, dc), 0.0)
    count = used.sum(axis=0)
    with np.errstate(invalid="ignore"):
        sat_mean = np.where(count > 0, v.sum(axis=0) / np.maximum(count, 1), np.nan)
    systems = tuple(dict.fromkeys(s[0] for s, c in zip(sats, count, strict=True) if c))
    letters = np.array([s[0] for s in sats])
    sys_count = np.array([int(count[letters == s].sum()) for s in systems], dtype=np.int64)
    sys_mean = np.array(
        [
            float(v[:, letters == s].sum()) / max(int(c), 1)
            for s, c in zip(systems, sys_count, strict=True)
        ]
    )
    return ResidualBias(
        sats=tuple(sats),
        sat_mean_m=sat_mean,
        sat_count=count.astype(np.int64),
        systems=systems,
        system_mean_m=sys_mean,
        system_count=sys_count,
    )
