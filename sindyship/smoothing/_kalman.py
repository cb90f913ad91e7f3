"""The Kalman (RTS) smoother of a record's kinematics."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import SindyshipInputError
from ..trajectory import Trajectory
from ._noise import estimate_noise
from ._settings import _CUTOFF_TIMES_WINDOW, RTS_CHANNELS, SmoothingSetting

# ---------------------------------------------------------------------------------------------
# Kalman filter and Rauch-Tung-Striebel smoother
# ---------------------------------------------------------------------------------------------
# State order: x, y, psi, u, v, r, a_u, a_v, a_r; the first six are measured.  Every function
# works on a batch of records of equal length (leading axis B).
_N = 9
_M = 6
_IX, _IY, _IPSI, _IU, _IV, _IR, _IAU, _IAV, _IAR = range(_N)
# Taylor weights of the Van Loan integral for a nilpotent A (A^4 = 0):
# Q = sum_{j,k} A^j G A^kT dt^(j+k+1) / (j! k! (j+k+1)).
_POW = np.arange(4)
_FACT = np.array([1.0, 1.0, 2.0, 6.0])
#: Variance (in units of the noise variance) that stands for a missing measurement.
_MISSING = 1e12


def _kinematics(z: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Earth-fixed velocity at time s into a step with constant accelerations."""
    psi = z[:, _IPSI] + z[:, _IR] * s + 0.5 * z[:, _IAR] * s * s
    u = z[:, _IU] + z[:, _IAU] * s
    v = z[:, _IV] + z[:, _IAV] * s
    c, sn = np.cos(psi), np.sin(psi)
    return u * c - v * sn, u * sn + v * c


def _propagate(z: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """Mean state after dt: exact for the chains, Simpson's rule for the positions."""
    out = z.copy()
    x0, y0 = _kinematics(z, 0.0 * dt)
    xm, ym = _kinematics(z, 0.5 * dt)
    x1, y1 = _kinematics(z, dt)
    out[:, _IX] += dt / 6.0 * (x0 + 4.0 * xm + x1)
    out[:, _IY] += dt / 6.0 * (y0 + 4.0 * ym + y1)
    out[:, _IPSI] += z[:, _IR] * dt + 0.5 * z[:, _IAR] * dt * dt
    out[:, _IU] += z[:, _IAU] * dt
    out[:, _IV] += z[:, _IAV] * dt
    out[:, _IR] += z[:, _IAR] * dt
    return out


def _jacobian(z: np.ndarray) -> np.ndarray:
    """Continuous-time Jacobians of the dynamics, shape (B, 9, 9); nilpotent (A^4 = 0)."""
    A = np.zeros((z.shape[0], _N, _N))
    c, s = np.cos(z[:, _IPSI]), np.sin(z[:, _IPSI])
    u, v = z[:, _IU], z[:, _IV]
    A[:, _IX, _IPSI] = -u * s - v * c
    A[:, _IX, _IU] = c
    A[:, _IX, _IV] = -s
    A[:, _IY, _IPSI] = u * c - v * s
    A[:, _IY, _IU] = s
    A[:, _IY, _IV] = c
    A[:, _IPSI, _IR] = 1.0
    A[:, _IU, _IAU] = 1.0
    A[:, _IV, _IAV] = 1.0
    A[:, _IR, _IAR] = 1.0
    return A


def _transition(A: np.ndarray, G: np.ndarray, dt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact F = expm(A dt) and the Van Loan process covariance, for nilpotent A."""
    B = A.shape[0]
    powers = np.empty((B, 4, _N, _N))
    powers[:, 0] = np.eye(_N)
    for k in range(1, 4):
        powers[:, k] = powers[:, k - 1] @ A
    tau = dt[:, None] ** _POW / _FACT  # (B, 4)
    F = np.einsum("bj,bjac->bac", tau, powers)
    jk = _POW[:, None] + _POW[None, :]
    weights = (dt[:, None, None] ** (jk + 1)
               / (_FACT[:, None] * _FACT[None, :] * (jk + 1)))  # (B, 4, 4)
    left = powers @ G[:, None]  # A^j G, (B, 4, N, N)
    right = np.einsum("bjk,bkdc->bjcd", weights, powers)  # sum_k w_jk (A^k)^T
    Q = (np.swapaxes(left, 1, 2).reshape(B, _N, 4 * _N)
         @ right.reshape(B, 4 * _N, _N))
    return F, 0.5 * (Q + np.swapaxes(Q, 1, 2))


def _noise_levels(record: Trajectory, noise: Mapping[str, float]) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """(levels used, levels given or estimated) of x, y, psi, u, v, r for one record."""
    unknown = sorted(set(noise) - set(RTS_CHANNELS))
    if unknown:
        raise SindyshipInputError(
            f"no measurement noise can be given for {unknown[0]!r}; the Kalman smoother "
            f"measures {', '.join(RTS_CHANNELS)}."
        )
    estimated = np.empty(_M)
    for j, channel in enumerate(RTS_CHANNELS):
        given = noise.get(channel)
        if given is None:
            estimated[j] = estimate_noise(record[channel])
            continue
        if not (isinstance(given, int | float) and math.isfinite(given) and given >= 0):
            raise SindyshipInputError(
                f"the noise level of {channel!r} must be a finite number >= 0, not {given!r}."
            )
        estimated[j] = float(given)
    # a floor keeps the filter well posed on noise-free data
    meas = np.column_stack([record[c] for c in RTS_CHANNELS])
    rms = np.sqrt(np.nanmean(meas**2, axis=0))
    floor = 1e-9 * np.where(np.isfinite(rms) & (rms > 0), rms, 1.0)
    return np.maximum(estimated, floor), estimated


def _rts_batch(t: np.ndarray, meas: np.ndarray, sigma: np.ndarray, window: float
               ) -> np.ndarray:
    """Extended Kalman filter and RTS smoother for B records of N samples.

    Parameters
    ----------
    t : ndarray, shape (B, N)
        Sample times [s], increasing.
    meas : ndarray, shape (B, N, 6)
        Measured x, y, psi, u, v, r (SI); NaN where missing.
    sigma : ndarray, shape (B, 6)
        Measurement noise standard deviations (positive).
    window : float
        Savitzky-Golay window of the same cut-off [s] (module docstring).

    Returns
    -------
    ndarray, shape (B, N, 9)
        Smoothed states in SI.
    """
    B, n, _ = meas.shape
    dt_typ = np.median(np.diff(t, axis=1), axis=1)  # (B,)
    omega = 2.0 * math.pi * _CUTOFF_TIMES_WINDOW / window
    # jerk spectral densities from the cut-off, w_c^4 = q / (sigma^2 dt), and a trace of
    # position diffusion for numerical health (model error of the kinematics)
    G = np.zeros((B, _N, _N))
    for j, i in ((3, _IAU), (4, _IAV), (5, _IAR)):
        G[:, i, i] = sigma[:, j] ** 2 * dt_typ * omega**4
    q_p = 1e-6 * np.minimum(sigma[:, 0], sigma[:, 1]) ** 2 / dt_typ
    G[:, _IX, _IX] = q_p
    G[:, _IY, _IY] = q_p
    # scaled coordinates: measured states in units of their noise, accelerations in units of
    # sigma * omega, so that R = I and every covariance entry is of order one
    D = np.concatenate([sigma, sigma[:, 3:] * omega], axis=1)  # (B, N)
    Dinv = 1.0 / D
    scaled = meas * Dinv[:, None, :_M]
    missing = ~np.isfinite(scaled)
    scaled = np.where(missing, 0.0, scaled)

    # a vague prior: the first complete sample with ten noise standard deviations, and
    # accelerations as large as the steepest finite difference of the record
    m = np.zeros((B, _N))
    P = np.zeros((B, _N, _N))
    eye = np.eye(_N)
    for b in range(B):
        complete = np.flatnonzero(~missing[b].any(axis=1))
        m[b, :_M] = scaled[b, complete[0]]
        rates = np.abs(np.diff(meas[b, complete, 3:], axis=0)) / np.diff(t[b, complete])[:, None]
        acc = np.maximum(np.nanmax(rates, axis=0, initial=0.0), sigma[b, 3:] * omega)
        P[b] = np.diag(np.concatenate([np.full(_M, 100.0), (10.0 * acc * Dinv[b, _M:]) ** 2]))
    m_pred = np.empty((B, n, _N))
    P_pred = np.empty((B, n, _N, _N))
    m_filt = np.empty((B, n, _N))
    P_filt = np.empty((B, n, _N, _N))
    F_all = np.empty((B, n, _N, _N))
    rows = np.arange(_M)
    for k in range(n):
        if k > 0:
            dt = t[:, k] - t[:, k - 1]
            z = m_filt[:, k - 1] * D
            F, Q = _transition(_jacobian(_propagate(z, 0.5 * dt)), G, dt)
            Fs = F * Dinv[:, :, None] * D[:, None, :]
            m = _propagate(z, dt) * Dinv
            P = Fs @ P_filt[:, k - 1] @ np.swapaxes(Fs, 1, 2) + Q * (Dinv[:, :, None]
                                                                      * Dinv[:, None, :])
            F_all[:, k] = Fs
        m_pred[:, k] = m
        P_pred[:, k] = P
        # measurement update, H = [I 0], R = I (a missing value: a huge variance)
        R = np.where(missing[:, k], _MISSING, 1.0)
        S = P[:, :_M, :_M].copy()
        S[:, rows, rows] += R
        K = np.swapaxes(np.linalg.solve(S, P[:, :_M, :]), 1, 2)  # (B, N, M)
        innovation = np.where(missing[:, k], 0.0, scaled[:, k] - m[:, :_M])
        m = m + np.einsum("bij,bj->bi", K, innovation)
        IKH = np.broadcast_to(eye, P.shape).copy()
        IKH[:, :, :_M] -= K
        P = IKH @ P @ np.swapaxes(IKH, 1, 2) + (K * R[:, None, :]) @ np.swapaxes(K, 1, 2)
        P = 0.5 * (P + np.swapaxes(P, 1, 2))
        m_filt[:, k] = m
        P_filt[:, k] = P
    smooth = np.empty((B, n, _N))
    smooth[:, -1] = m_filt[:, -1]
    for k in range(n - 2, -1, -1):
        gain_t = np.linalg.solve(P_pred[:, k + 1], F_all[:, k + 1] @ P_filt[:, k])
        step = smooth[:, k + 1] - m_pred[:, k + 1]
        smooth[:, k] = m_filt[:, k] + np.einsum("bji,bj->bi", gain_t, step)
    return smooth * D[:, None, :]


def _rts_records(records: Sequence[Trajectory], setting: SmoothingSetting,
                 noise: Mapping[str, float]) -> list[Trajectory]:
    """The Kalman smoother on records, batching records of equal length."""
    levels = []
    for record in records:
        name = record.name or "the record"
        steps = np.diff(record.t)
        if not np.all(steps > 0):
            raise SindyshipInputError(f"{name}: time must increase from sample to sample.")
        meas = np.column_stack([record[c] for c in RTS_CHANNELS])
        if np.count_nonzero(np.all(np.isfinite(meas), axis=1)) < 5:
            raise SindyshipInputError(
                f"{name}: fewer than 5 samples have all of {', '.join(RTS_CHANNELS)}; "
                "there is too little to smooth."
            )
        levels.append(_noise_levels(record, noise))
    out: list[Trajectory | None] = [None] * len(records)
    groups: dict[int, list[int]] = {}
    for i, record in enumerate(records):
        groups.setdefault(record.n_samples, []).append(i)
    for idx in groups.values():
        t = np.stack([records[i].t for i in idx])
        meas = np.stack([np.column_stack([records[i][c] for c in RTS_CHANNELS]) for i in idx])
        sigma = np.stack([levels[i][0] for i in idx])
        with np.errstate(over="ignore", invalid="ignore"):
            states = _rts_batch(t, meas, sigma, setting.window)
        for b, i in enumerate(idx):
            record = records[i]
            data = record.data.copy()
            for j, channel in enumerate(RTS_CHANNELS):
                data[channel] = states[b, :, j]
            meta = {
                **record.meta,
                "smoothing": {**setting.as_dict(),
                              "noise": dict(zip(RTS_CHANNELS, levels[i][1].tolist(),
                                                strict=True)),
                              "noise_given": sorted(noise)},
                "accelerations": tuple(states[b, :, j].copy() for j in (_IAU, _IAV, _IAR)),
            }
            out[i] = Trajectory(data, name=record.name, meta=meta)
    return out  # type: ignore[return-value]
