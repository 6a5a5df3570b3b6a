"""``plan --target azimuth_*`` for a rate gyro: time per position and number of positions from the
Fisher information (issue 35 item 3).

The bound is the estimator's own (:mod:`.rate_gyro`): J = Hᵀ C⁻¹ H of the bin means of the
schedule the instrument would run (its index angles and settled samples, :func:`~gyro_instrument.
instruments.rate_gyro.schedule`), the noise the instrument's datasheet figures give (white ARW,
Gauss–Markov bias instability), at the scene's true mount azimuth (two positions: σ depends on it,
σ_M = σ_d / (A |sin(M + φ0)|)). No data are drawn: σ(T) is exact for the model.

Planned: with the scene's own schedule (its positions, dwell and slew), the number of whole sequences
whose record reaches the target (``observation_s``: what ``--verify`` runs); beside it, the schedule
that reaches it soonest among 2 (only with a prior that resolves the mirror image), 4 and 8 positions
and dwells from 30 s to 40 min (the bias instability favours short dwells revisited; the slews' dead
time, long ones). A carousel: T for the scene's turn rate, and the same at a few other rates; beyond 1 500 bins of 10° of
turn the bound is σ(T_ref) √(T_ref/T) (T_ref the record of 1 500 bins: 417 s at 36°/s, 4.2 τ_c of the
shipped MEMS), a slight overstatement of σ where the bias instability still correlates the turns.

For long records the bound is computed at a coarser sample spacing Δ' (≤ 200 000 samples, Δ' ≤
τ_c/20 and ≤ dwell/20): a bin mean's white variance is ARW²/T_bin whatever Δ, and the Gauss–Markov's
sums change by O(Δ'/τ_c).
"""

import dataclasses
import math

import numpy as np

from gyro_instrument.estimators.north import rate_gyro as R
from gyro_instrument.instruments.rate_gyro import RATE_AZIMUTH, schedule

#: longest record planned (s): a week
MAX_PLAN_S = 7 * 86400.0
#: dwells tried (s) and position counts
DWELLS_S = (30.0, 60.0, 120.0, 300.0, 600.0, 1200.0, 2400.0)
POSITIONS = (2, 4, 8)
#: bins per bound evaluation (a dense Cholesky each); a carousel's record is bounded at most
#: CAROUSEL_BINS bins of 10° and extrapolated as T^(-1/2) beyond (its information adds turn by turn
#: once the record is many τ_c long)
PLAN_BINS = 400
CAROUSEL_BINS = 1500


def sigma_mount_rad(inst, p, duration_s, rate_hz) -> float:
    """σ of the mount azimuth (rad) at the Cramér–Rao bound for a record of ``duration_s`` with the
    parameters ``p`` (the instrument's, possibly replaced); inf when the schedule cannot give north."""
    dt = 1.0 / rate_hz
    if p.carousel_rate_deg_s:
        ref_s = CAROUSEL_BINS * math.degrees(R.CAROUSEL_BIN_RAD) / abs(p.carousel_rate_deg_s)
        if duration_s > ref_s:            # many turns: information adds, σ ∝ T^(-1/2) (module docstring)
            return sigma_mount_rad(inst, p, ref_s, rate_hz) * math.sqrt(ref_s / duration_s)
        limit = 0.1 / abs(p.carousel_rate_deg_s)                     # a tenth of a degree of turn per sample
    else:
        limit = min(p.bias_correlation_time_s / 20.0, p.dwell_s / 20.0)
    dt = max(dt, min(duration_s / 200000.0, limit))
    n = int(math.floor(duration_s / dt + 1e-9)) + 1
    t = np.arange(n) * dt
    phi, _ = schedule(t, p)
    obs = inst.observation()
    noise = obs.noise_model(dt)
    carousel = bool(p.carousel_rate_deg_s)
    d = R.design(np.arange(n), phi, carousel, noise, dt, 360.0 / abs(p.carousel_rate_deg_s) if carousel else None,
                 CAROUSEL_BINS if carousel else PLAN_BINS)
    if len(d["bins"]) < 3:
        return math.inf
    M, phi0 = math.radians(p.mount_azimuth_deg), math.radians(p.first_index_deg)
    A = (1.0 + 1e-6 * p.scale_factor_ppm) * inst.horizontal_rate_rad_s()
    head = R.headings(d, phi0)["count"]
    if carousel or head >= 3:
        J = R.gls(d["H"], d["C"])[1]
        g = np.array([-math.sin(M), math.cos(M), 0.0]) / A
        return float(math.sqrt(g @ np.linalg.solve(J, g)))
    if head == 2:
        u = d["H"][:, 0] * math.cos(phi0) - d["H"][:, 1] * math.sin(phi0)
        J = R.gls(np.column_stack([u, np.ones_like(u)]), d["C"])[1]
        s = abs(math.sin(M + phi0))
        return float(math.sqrt(np.linalg.inv(J)[0, 0]) / (A * s)) if s > 0 else math.inf
    return math.inf


def _sequences_needed(inst, p, si, rate_hz) -> tuple:
    """(sequences, T s, σ rad) of the fewest whole sequences of ``p``'s schedule reaching σ ≤ ``si`` (to
    2 %: a bracket from the σ ∝ R^(−1/2) guess, then bisection), or (None, None, σ at the longest
    record planned)."""
    seq_s = p.positions * (p.dwell_s + p.slew_s)
    top = max(int(MAX_PLAN_S // seq_s), 1)
    memo = {}

    def sig(r):
        if r not in memo:
            memo[r] = sigma_mount_rad(inst, p, r * seq_s - p.slew_s, rate_hz)
        return memo[r]
    if not math.isfinite(sig(1)):
        return None, None, math.inf
    guess = min(max(math.ceil((sig(1) / si) ** 2), 1), top)
    if sig(guess) > si:
        lo, hi = guess, guess
        while sig(hi) > si:
            if hi >= top:
                return None, None, sig(top)
            lo, hi = hi, min(max(math.ceil(hi * (sig(hi) / si) ** 2 * 1.1), hi + 1), top)
    else:
        lo, hi = guess, guess
        while lo > 0 and sig(lo) <= si:
            hi, lo = lo, math.floor(lo * (sig(lo) / si) ** 2 * 0.9) if lo > 1 else 0
    while hi - lo > max(1, int(0.02 * hi)):
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if sig(mid) > si else (lo, mid)
    return hi, hi * seq_s - p.slew_s, sig(hi)


def _carousel_time(inst, p, si, rate_hz) -> tuple:
    """(T s, σ rad) of the shortest carousel record reaching ``si``, or (None, σ at the longest): beyond
    the reference record T = T_ref (σ_ref/si)² (the T^(-1/2) law), within it a bisection in log T."""
    ref_s = CAROUSEL_BINS * math.degrees(R.CAROUSEL_BIN_RAD) / abs(p.carousel_rate_deg_s)

    def sig(T):
        return sigma_mount_rad(inst, p, T, rate_hz)
    s_ref = sig(ref_s)
    if s_ref > si:
        T = ref_s * (s_ref / si) ** 2
        return (T, si) if T <= MAX_PLAN_S else (None, sig(MAX_PLAN_S))
    lo, hi = 360.0 / abs(p.carousel_rate_deg_s), ref_s
    if sig(lo) <= si:
        return lo, sig(lo)
    while hi / lo > 1.01:
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if sig(mid) > si else (lo, mid)
    return hi, sig(hi)


def plan_target(scene, gyros, name, value, si, unit_rad) -> dict:
    """The plan entry of an azimuth target for the scene's rate gyros (the one needing least time leads)."""
    rows = {n: _plan_one(scene, inst, si, unit_rad) for n, inst in gyros.items()}
    ok = {n: r for n, r in rows.items() if r.get("observation_s") is not None}
    entry = {"target": name, "value": value, "quantity": "azimuth", "kind": RATE_AZIMUTH}
    if not ok:
        entry.update({"observation_s": None, "reason": "; ".join(f"{n}: {r['reason']}" for n, r in rows.items()),
                      "rate_gyros": rows})
        return entry
    best = min(ok, key=lambda n: ok[n]["observation_s"])
    entry.update(ok[best] | {"instrument": best, "rate_gyros": rows})
    return entry


def _plan_one(scene, inst, si, unit_rad) -> dict:
    p, rate = inst.p, scene.sample_rate_hz
    out = {"mount_azimuth_deg_truth": p.mount_azimuth_deg % 360.0, "method": "gls",
           "limited_by": "noise: the Cramer-Rao bound of the bin means (white ARW + Gauss-Markov bias instability)",
           "floor": _floor(inst, unit_rad)}
    if p.carousel_rate_deg_s:
        T, s = _carousel_time(inst, p, si, rate)
        out["schedule"] = {"carousel_rate_deg_s": p.carousel_rate_deg_s}
        out["alternatives"] = [{"carousel_rate_deg_s": w, "observation_s": _carousel_time(
            inst, dataclasses.replace(p, carousel_rate_deg_s=w), si, rate)[0]} for w in (6.0, 36.0, 180.0)]
    else:
        seqs, T, s = _sequences_needed(inst, p, si, rate)
        out["schedule"] = {"positions": p.positions, "dwell_s": p.dwell_s, "slew_s": p.slew_s, "sequences": seqs,
                           "time_per_position_s": None if seqs is None else seqs * p.dwell_s}
        out["alternatives"] = _alternatives(inst, p, si, rate)
    if T is None:
        out.update(observation_s=None, reason=f"not reached within {MAX_PLAN_S:g} s ({s / unit_rad:.4g} there)")
        return out
    out.update(observation_s=T, planned_sigma=s / unit_rad, samples_per_instrument=int(math.floor(T * rate + 1e-9)) + 1)
    return out


def _alternatives(inst, p, si, rate) -> list:
    """The fewest-time schedule per position count (2 only when the prior resolves the mirror image)."""
    rows = []
    for P in POSITIONS:
        if P == 2 and p.mount_azimuth_prior_tolerance_deg >= 90.0:
            continue
        best = None
        for dwell in DWELLS_S:
            q = dataclasses.replace(p, positions=P, dwell_s=dwell)
            seqs, T, s = _sequences_needed(inst, q, si, rate)
            if T is not None and (best is None or T < best["observation_s"]):
                best = {"positions": P, "dwell_s": dwell, "slew_s": p.slew_s, "sequences": seqs, "observation_s": T,
                        "time_per_position_s": seqs * dwell}
        rows.append(best or {"positions": P, "observation_s": None})
    return rows


def _floor(inst, unit_rad) -> dict:
    """The estimator's bias in this set-up: none for ≥ 3 headings (the model is exact); with two, a scale
    factor error s moves north by s cot(M + φ0) (the amplitude is assumed n cos γ)."""
    p = inst.p
    if p.carousel_rate_deg_s or p.positions != 2:
        return {"bias": 0.0, "reachable": True, "reason": "the linear model is exact; scale factor and bias are fitted"}
    psi = math.radians(p.mount_azimuth_deg + p.first_index_deg)
    b = 1e-6 * p.scale_factor_ppm * math.cos(psi) / math.sin(psi) if math.sin(psi) else math.inf
    return {"bias": b / unit_rad, "reachable": None,
            "reason": "two positions assume the amplitude n cos(latitude): the scale factor error s moves north by "
                      "s cot(M + phi0)"}


def plan_lines(e) -> list:
    """An azimuth target's plan for rate gyros, as lines (``plan`` text)."""
    unit = e["target"][len("azimuth_"):]
    out = [f"target {e['target']} = {e['value']:g} (1 sigma), rate gyro north finder:"]
    if e.get("observation_s") is None:
        return out + [f"  not reachable: {e.get('reason')}"]
    s = e["schedule"]
    how = (f"carousel at {s['carousel_rate_deg_s']:g} deg/s" if "carousel_rate_deg_s" in s else
           f"{s['positions']} positions x {s['dwell_s']:g} s (slew {s['slew_s']:g} s), {s['sequences']} sequence(s): "
           f"{s['time_per_position_s']:g} s per position")
    out.append(f"  observe {e['observation_s']:.6g} s with {e['instrument']} ({how}): least squares at the Cramer-Rao "
               f"bound {e['planned_sigma']:.4g} {unit}")
    for a in e.get("alternatives", []):
        if a.get("observation_s") is None:
            continue
        what = (f"carousel {a['carousel_rate_deg_s']:g} deg/s" if "carousel_rate_deg_s" in a else
                f"{a['positions']} positions x {a['dwell_s']:g} s x {a['sequences']}")
        out.append(f"    alternative: {what}: {a['observation_s']:.6g} s")
    fl = e.get("floor") or {}
    out.append(f"  floor: {fl.get('bias', 0.0):.3g} {unit} ({fl.get('reason')})")
    return out
