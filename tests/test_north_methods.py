"""North from the swing (issue 24, items 3 and 6): gyro_instrument.estimators.north and field_book.

Synthetic records are analytic damped sinusoids (north.damped_swing) with a known centre and white
noise; every tolerance says where it comes from.
"""

import math

import numpy as np
import pytest

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.north import field_book as fb
from gyro_instrument.estimators import north

# a gyroscope swinging with a 20 s period (Quet's T = 10 s), 0.05 rad amplitude, read at 20 Hz
PERIOD = 20.0
W = 2 * math.pi / PERIOD
AMP = 0.05
CENTRE = 0.0123
PHASE = 0.3
SIGMA = 2e-5            # sensor noise (rad, ~4″)


def record(duration=100.0, rate=20.0, damping=0.0, seed=None, centre=CENTRE, drift=0.0):
    t = np.arange(0.0, duration, 1.0 / rate)
    u = north.damped_swing(t, centre, AMP, W, damping, PHASE, drift)
    if seed is not None:
        u = u + np.random.default_rng(seed).normal(0.0, SIGMA, t.size)
    return t, u


def true_turning_points(t, damping):
    """Turning points of c + A e^(−δt) cos(ωt + φ): tan(ωt + φ) = −δ/ω, equally spaced by π/ω."""
    k = np.arange(-2, int(t[-1] * W / math.pi) + 3)
    tt = (math.atan(-damping / W) - PHASE + math.pi * k) / W
    tt = tt[(tt > t[0]) & (tt < t[-1])]
    return tt, north.damped_swing(tt, CENTRE, AMP, W, damping, PHASE)


# ----------------------------------------------------------------------------- conventions
def test_mount_azimuth_is_minus_the_north_reading():
    """u = azimuth(axis) − mount_azimuth; the axis at true north (azimuth 0) reads −mount_azimuth."""
    for mount_deg in (0.0, 30.0, 200.0, 359.5):
        reading = (0.0 - math.radians(mount_deg) + math.pi) % (2 * math.pi) - math.pi
        assert math.degrees(north.mount_azimuth_rad(reading)) == pytest.approx(mount_deg % 360, abs=1e-9)
    est = north.NorthEstimate("x", -math.radians(30.0), None, "none", 3, "")
    assert math.degrees(est.mount_azimuth_rad) == pytest.approx(30.0, abs=1e-12)
    assert est.to_dict()["centre_rad"] == est.centre_rad


# ----------------------------------------------------------------------------- Schuler mean
def test_schuler_weights_are_the_printed_formula():
    """L = (a1 + 3a2 + 4a3 + … + 4a(ν−2) + 3a(ν−1) + aν)/(4(ν−2)) on hand numbers (FFH A 303 eq. 31b)."""
    a = [10.0, -6.0, 9.0, -5.0, 8.2, -4.4, 7.5]
    for nu in (4, 5, 7):
        x = a[:nu]
        literal = (x[0] + 3 * x[1] + 4 * sum(x[2:nu - 2]) + 3 * x[nu - 2] + x[nu - 1]) / (4 * (nu - 2))
        assert north.schuler_mean(x).centre_rad == pytest.approx(literal, rel=1e-15)
    # ν = 4 by hand: (10 − 18 + 27 − 5)/8 = 1.75
    assert north.schuler_mean(a[:4]).centre_rad == pytest.approx(1.75, rel=1e-15)
    assert north.schuler_weights(3) == pytest.approx([0.25, 0.5, 0.25])


def test_schuler_mean_is_exact_for_linear_decay_and_second_order_for_exponential():
    """Linear decay of the half-amplitude: each triple sum vanishes (exact to rounding). Geometric
    deviations d1(−q)^(i−1): the bias is north.schuler_bias (derived there), second order in 1 − q."""
    c = 0.3
    i = np.arange(9)
    linear = c + (-1.0) ** i * (0.05 - 0.002 * i)
    assert north.schuler_mean(linear).centre_rad == pytest.approx(c, abs=1e-15)
    for q in (0.9, 0.97):
        a = c + 0.05 * (-q) ** i
        bias = north.schuler_mean(a).centre_rad - c
        assert bias == pytest.approx(north.schuler_bias(0.05, q, i.size), rel=1e-9)
    small, smaller = (abs(north.schuler_bias(0.05, q, 9)) for q in (0.98, 0.99))
    assert smaller / small == pytest.approx(0.25, rel=0.05)        # ∝ (1 − q)²: halving 1 − q quarters it


def test_schuler_sigma_propagated_and_from_the_scatter():
    w = north.schuler_weights(5)
    est = north.schuler_mean([1.0, -1.0, 1.0, -1.0, 1.0], sigmas=2e-3)
    assert est.sigma_rad == pytest.approx(2e-3 * math.sqrt(np.sum(w ** 2)), rel=1e-12)
    three = north.schuler_mean([1.0, -1.0, 0.9])
    assert three.sigma_rad is None and "no scatter" in three.sigma_source
    # the scatter estimate is unbiased in σ²: mean of σ̂² over many books ≈ σ_L² (3 % ≈ 3/√(2·1000·6))
    rng = np.random.default_rng(7)
    base = 0.1 + (-1.0) ** np.arange(9) * np.linspace(0.05, 0.03, 9)
    s2 = [north.schuler_mean(base + rng.normal(0, 1e-3, 9)).sigma_rad ** 2 for _ in range(1000)]
    assert np.mean(s2) == pytest.approx(1e-6 * np.sum(north.schuler_weights(9) ** 2), rel=0.1)


# ----------------------------------------------------------------------------- Lavrov
def test_lavrov_is_exact_on_a_geometric_sequence():
    """a_i = c + d(−q)^(i−1): c = (a1 a3 − a2²)/(a1 + a3 − 2a2) exactly (derivation in lavrov_triples)."""
    a1, a2, a3 = 12.0, 6.0, 10.0            # hand numbers: (120 − 36)/(12 + 10 − 12) = 8.4
    assert north.lavrov_triples([a1, a2, a3])[0] == pytest.approx(8.4, rel=1e-15)
    c, d, q = 0.0123, 0.05, 0.93
    a = c + d * (-q) ** np.arange(8)
    assert north.lavrov_triples(a) == pytest.approx(np.full(6, c), abs=1e-15)
    est = north.lavrov(a)
    assert est.centre_rad == pytest.approx(c, abs=1e-14)
    assert north.lavrov(a[:3]).sigma_rad is None
    with pytest.raises(SceneError, match="alternate"):
        north.lavrov_triples([1.0, 2.0, 3.0])


# ----------------------------------------------------------------------------- reversal points
@pytest.mark.parametrize("damping", [0.0, 2e-3])
def test_reversal_points_noise_free_within_the_polynomial_bound(damping):
    """Degree-4 local fit over ±T/8 (ωh = π/4): the residual sextic term biases each peak by
    A(ωh)⁶/720 · (16/231)|P6(0)| = 5A(ωh)⁶/(720·231) = 7.1e-6 A (x⁶ less its quartic projection is
    (16/231)P6); 10 % over it for the damping's small change of shape."""
    t, u = record(duration=200.0, damping=damping)
    rp = north.reversal_points(t, u, noise_sigma_rad=1e-9)
    tt, tv = true_turning_points(t, damping)
    match = [int(np.argmin(abs(tt - x))) for x in rp.times_s]
    bound = 5 * AMP * (math.pi / 4) ** 6 / (720 * 231)
    assert np.max(np.abs(rp.readings_rad - tv[match])) <= 1.1 * bound
    inner = tt[(tt - t[0] >= PERIOD / 8) & (t[-1] - tt >= PERIOD / 8)]   # whole window in the record
    assert set(inner.round(3)) <= set(tt[match].round(3)) and len(set(match)) == len(match)
    assert np.max(np.abs(rp.times_s - tt[match])) < 1e-3                 # no spurious point
    assert rp.half_period_s == pytest.approx(PERIOD / 2, rel=1e-5)
    assert np.all(np.diff(np.sign(rp.readings_rad - CENTRE)) != 0)     # alternating


def test_reversal_point_sigmas_match_the_scatter():
    """rms(error)/σ over 200 seeds in [0.85, 1.15]: the rms of 200 × ~9 draws has a relative
    sampling error ≈ 1/√(2·1800) = 1.7 %; the range is wide to allow the ~0.4σ per-point fit bias."""
    t, u = record(duration=100.0)
    ref = north.reversal_points(t, u, SIGMA)
    rng = np.random.default_rng(11)
    err, sig = [], []
    for _ in range(200):
        rp = north.reversal_points(t, u + rng.normal(0, SIGMA, t.size), SIGMA)
        assert rp.readings_rad.size == ref.readings_rad.size
        err.append(rp.readings_rad - ref.readings_rad)
        sig.append(rp.sigmas_rad)
    assert 0.85 <= math.sqrt(np.mean(np.square(err))) / np.mean(sig) <= 1.15


# ----------------------------------------------------------------------------- transit method
def test_transit_offset_is_exact_for_a_sine():
    """For u = c + A cos ωt and a mark at c − x0 the crossings solve cos θ = −x0/A; time on the + side
    t₊ = (T/π)(π/2 + arcsin(x0/A)): x0 = A sin(πΔt/(2T)) recovers x0 to rounding."""
    for x0 in (0.001, 0.02, -0.04):
        tplus = PERIOD / math.pi * (math.pi / 2 + math.asin(x0 / AMP))
        dt = tplus - (PERIOD - tplus)
        assert north.transit_offset(dt, PERIOD, AMP) == pytest.approx(x0, rel=1e-12)


@pytest.mark.parametrize("offset", [0.0, 0.002, -0.02])
def test_transit_method_noise_free(offset):
    """Undamped: the crossing fits are degree 4 (a cubic's (ωh)⁴/280 relative error of the offset is
    gone; measured 7e-8 rad at 0.002 rad): tolerance 1e-7 rad (0.02″) + 1e-5 |offset|. Damped
    (δ = 2e-3/s): second order, x̂0 = x0 cosh(δT/4)(1 + cosh(δT/2))/2 ≈ x0 (1 + 3(δT)²/32)."""
    t, u = record(duration=200.0)
    est = north.transit_method(t, u, CENTRE + offset, 1e-9)
    assert est.centre_rad == pytest.approx(CENTRE, abs=1e-7 + 1e-5 * abs(offset))
    t, u = record(duration=200.0, damping=2e-3)
    est = north.transit_method(t, u, CENTRE + offset, 1e-9)
    predicted = -offset * 3 * (2e-3 * PERIOD) ** 2 / 32
    if abs(offset) / AMP <= 0.05:       # the derivation is first order in x0/A
        assert est.centre_rad - CENTRE == pytest.approx(predicted, abs=1e-7 + 0.3 * abs(predicted))
    else:                               # x0/A = 0.4: arcsin's curvature adds (measured ×1.6): the order
        assert 0.5 * abs(predicted) <= abs(est.centre_rad - CENTRE) <= 2 * abs(predicted)


def test_transit_mark_outside_the_swing_is_refused():
    t, u = record()
    with pytest.raises(SceneError, match="mark_rad.*inside the swing"):
        north.transit_method(t, u, CENTRE + 2 * AMP, SIGMA)


# ----------------------------------------------------------------------------- the fit and its bound
def test_crlb_closed_form():
    """σ(c) → σ/√N for many whole cycles; next order (1 + 3/(π²K²)) with ω, δ fitted (derived in
    crlb_centre); the next term is O(K⁻⁴): 2 % of the excess at K ≥ 10."""
    for cycles in (10, 20, 50):
        t = np.arange(0.0, cycles * PERIOD, 0.05)
        ratio = north.crlb_centre(t, AMP, W, SIGMA) / north.crlb_centre_long(SIGMA, t.size)
        assert ratio - 1 == pytest.approx(3 / (math.pi ** 2 * cycles ** 2), rel=0.02)


def test_fit_reaches_the_bound_over_seeds():
    """200 seeds, damped record with drift fitted: rms error / CRLB in [0.85, 1.15] (relative
    sampling error of an rms over 200 draws 1/√400 = 5 %: ±3 of it); mean error within 3 SE."""
    t, u = record(duration=60.0, damping=2e-3)
    bound = north.crlb_centre(t, AMP * math.exp(2e-3 * 30.0), W, SIGMA, 2e-3, PHASE + W * 30.0, drift=True)
    rng = np.random.default_rng(23)
    err, sig = [], []
    for _ in range(200):
        est = north.fit_record(t, u + rng.normal(0, SIGMA, t.size), SIGMA, drift=True)
        err.append(est.centre_rad - CENTRE)
        sig.append(est.sigma_rad)
    err = np.asarray(err)
    assert 0.85 <= math.sqrt(np.mean(err ** 2)) / bound <= 1.15
    assert abs(np.mean(err)) <= 3 * bound / math.sqrt(200)
    assert np.median(sig) == pytest.approx(bound, rel=0.01)        # σ at the estimate ≈ σ at the truth


def test_every_method_on_noisy_damped_records():
    """All four methods over 100 seeds: mean error within 3 SE plus each method's derived damping bias
    (Schuler: schuler_bias; transit at a mark 1e-3 rad off: x0·3(δT)²/32; Lavrov and the fit: none),
    and rms/σ in [0.8, 1.2] (an rms over 100 draws: relative sampling error 7 %, ±3 of it)."""
    damping, mark = 1e-3, CENTRE + 1e-3
    t, u = record(duration=120.0, damping=damping)
    tt, tv = true_turning_points(t, damping)
    rng = np.random.default_rng(5)
    res = {}
    for _ in range(100):
        methods, refused = north.north_methods(t, u + rng.normal(0, SIGMA, t.size), SIGMA, mark_rad=mark)
        assert not refused
        for name, est in methods.items():
            res.setdefault(name, []).append((est.centre_rad - CENTRE, est.sigma_rad, est.n_used))
    q = math.exp(-damping * PERIOD / 2)
    for name, rows in res.items():
        e, s, n = np.asarray(rows).T
        bias = {"schuler_mean": north.schuler_bias(tv[1] - CENTRE, q, int(n[0])) if n[0] == tt.size - 2 else None,
                "transit": -1e-3 * 3 * (damping * PERIOD) ** 2 / 32}.get(name, 0.0)
        if bias is not None:
            assert abs(np.mean(e) - bias) <= 3 * np.mean(s) / 10 + 0.2 * abs(bias), name
        assert 0.8 <= math.sqrt(np.mean((e - np.mean(e)) ** 2)) / np.mean(s) <= 1.2, name
    assert np.mean(np.asarray(res["fit"])[:, 1]) < np.mean(np.asarray(res["schuler_mean"])[:, 1])


# ----------------------------------------------------------------------------- the tape
def test_tape_ratio_and_correction_on_a_two_period_case():
    """Rotor off: a torsion pendulum about the tape zero Z, ω_off² = D_B/J; rotor on: about
    c = (D_K N + D_B Z)/(D_K + D_B), ω_on² = (D_K + D_B)/J. Fitting both swings and correcting gives
    N within 4σ (σ propagated through tape_corrected), and D_B/D_K = T_on²/(T_off² − T_on²)."""
    J, D_K, D_B = 1e-2, 1e-3, 2.5e-4
    N_true, Z = -0.5236, -0.51
    w_on, w_off = math.sqrt((D_K + D_B) / J), math.sqrt(D_B / J)
    c = (D_K * N_true + D_B * Z) / (D_K + D_B)
    rng = np.random.default_rng(3)
    t_on, t_off = np.arange(0, 120, 0.05), np.arange(0, 300, 0.05)
    on = north.fit_record(t_on, north.damped_swing(t_on, c, 0.03, w_on, 1e-3, 0.2)
                          + rng.normal(0, SIGMA, t_on.size), SIGMA)
    off = north.fit_record(t_off, north.damped_swing(t_off, Z, 0.02, w_off, 1e-3, 1.0)
                           + rng.normal(0, SIGMA, t_off.size), SIGMA)
    ratio, ratio_sigma = north.tape_ratio(on.period_s, off.period_s, on.period_sigma_s, off.period_sigma_s)
    assert ratio == pytest.approx(D_B / D_K, abs=4 * ratio_sigma)
    assert north.tape_ratio(2 * math.pi / w_on, 2 * math.pi / w_off)[0] == pytest.approx(D_B / D_K, rel=1e-12)
    est = north.tape_corrected(on, off.centre_rad, ratio, ratio_sigma, off.sigma_rad)
    assert est.method == "fit+tape"
    assert est.centre_rad == pytest.approx(N_true, abs=4 * est.sigma_rad)
    assert abs(on.centre_rad - N_true) > 100 * est.sigma_rad        # the tape's pull is real
    with pytest.raises(SceneError, match=r"period_off_s = 10\.0 .*cancels or reverses"):
        north.tape_ratio(12.0, 10.0)


# ----------------------------------------------------------------------------- field books
def test_field_book_round_trip_gives_what_the_run_gives(tmp_path):
    """A field book written (full precision, gon) from a simulated run's reversal points gives the
    same Schuler mean and Lavrov estimate as the run's own points: equal to 1e-15 rad (unit round trip)."""
    t, u = record(duration=200.0, damping=1e-3, seed=1)
    rp = north.reversal_points(t, u, SIGMA)
    path = tmp_path / "book.csv"
    fb.write_field_book(path, rp.readings_rad, rp.times_s, angle_unit="gon")
    book = fb.read_field_book(path)
    assert book.angle_unit == "gon" and book.times_s == pytest.approx(rp.times_s, abs=1e-12)
    got = fb.field_book_north(book)
    assert got["schuler_mean"].centre_rad == pytest.approx(north.schuler_mean(rp.readings_rad).centre_rad, abs=1e-15)
    assert got["lavrov"].centre_rad == pytest.approx(north.lavrov(rp.readings_rad).centre_rad, abs=1e-15)
    assert got["schuler_mean"].sigma_rad is not None and "scatter" in got["schuler_mean"].sigma_source


def test_field_book_units_wrap_and_tape(tmp_path):
    path = tmp_path / "b.csv"
    path.write_text("# hand-written\ntime_min,reading\n0,359.9\n1,0.2\n2,359.92\n3,0.18\n")
    book = fb.read_field_book(path, angle_unit="deg")
    assert np.degrees(book.readings_rad) == pytest.approx([359.9, 360.2, 359.92, 360.18])
    assert book.times_s == pytest.approx([0, 60, 120, 180]) and "unwrapped" in book.notes[0]
    path.write_text("reading_arcmin,time_s,tape_reading_arcmin,tape_time_s\n10,0,3,0\n-8,5,-2,8\n9,10,2.5,16\n-7,15,,\n")
    book = fb.read_field_book(path)
    assert book.tape_readings_rad == pytest.approx(np.radians(np.array([3, -2, 2.5]) / 60))
    est = fb.field_book_north(book)["schuler_mean"]
    # issue 33: the ratio from the *undamped* half periods (T_on 5 s, T_off 8 s; δ = −ln(q)/T with Lavrov's
    # damping ratio per swing q) and the exact relation N = c − atan(x (Z − c)); q of the 3 tape points in
    # closed form (a_i = c + d(−q)^i), q of the 4 rotor-on points from Lavrov's fit (its note)
    c, z = north.schuler_mean(book.readings_rad).centre_rad, north.schuler_mean(book.tape_readings_rad).centre_rad
    a = book.tape_readings_rad
    z_lav = float(north.lavrov_triples(a)[0])
    q_off = -(a[1] - z_lav) / (a[0] - z_lav)
    q_on = float(north.lavrov(book.readings_rad).notes[0].split("=")[1])
    w_on2, w_off2 = ((math.pi / T) ** 2 + (math.log(q) / T) ** 2 for T, q in ((5.0, q_on), (8.0, q_off)))
    x = w_off2 / (w_on2 - w_off2)
    assert est.centre_rad == pytest.approx(c - math.atan(x * (z - c)), rel=1e-9)   # q_on printed to 6 digits
    assert abs(est.centre_rad - (c + 5.0 ** 2 / (8.0 ** 2 - 5.0 ** 2) * (c - z))) > 1e-8  # not the damped, linear law


@pytest.mark.parametrize("text, option, match", [
    ("reading_deg\n1\n-1\nx\n", None, r"line 4, column reading_deg: 'x' is not a number"),
    ("reading_deg\n1\n-1\n400\n", None, r"line 4, column reading_deg: '400' is outside the circle \(one turn\)"),
    ("reading_deg\n1\n-1\n-2\n", None, r"line 4, column reading_deg: '-2': turning points must alternate"),
    ("reading_deg,time_s\n1,0\n-1,5\n1,5\n", None, r"line 4, column time_s: '5' must be later"),
    ("reading\n1\n-1\n1\n", None, r"column 'reading' states no unit"),
    ("reading_deg\n1\n-1\n1\n", "gon", r"--angle-unit = 'gon' is invalid: contradicts the header"),
    ("reading_deg,speed\n1,0\n-1,0\n1,0\n", None, r"column 'speed' is not a field-book column"),
    ("reading_deg\n1\n\n-1\n1\n", None, None),                                   # blank lines are skipped
    ("reading_deg,time_s\n1,0\n,5\n1,6\n", None, r"holds 2 turning point readings"),   # a hole kept out by its time
    ("reading_deg,time_s\n1,0\n,5\n1,10\n-1,15\n", None, None),                        # ... and the rest kept
    ("reading_deg\n1\n-1\n", None, r"holds 2 turning point readings"),
])
def test_field_book_bad_input_names_line_column_value_and_range(tmp_path, text, option, match):
    path = tmp_path / "b.csv"
    path.write_text(text)
    if match is None:
        assert fb.read_field_book(path, angle_unit=option).readings_rad.size == 3
        return
    with pytest.raises(SceneError, match=match):
        fb.read_field_book(path, angle_unit=option)


def test_bench_study_rows():
    """The bench study (gyro_instrument.bench.north_study): one row per method and time; the fit's σ
    is its bound (1 %: σ at the estimate vs at the truth), its noise-free floor ≪ the bound; a record
    too short for two reversal points is refused, not estimated."""
    from gyro_instrument.bench.north_study import north_accuracy_vs_time
    rows = north_accuracy_vs_time([5.0, 60.0], damping_per_s=1e-3, seeds=3)
    assert rows[0]["method"] == "all" and "observe longer" in rows[0]["refused"]
    by = {r["method"]: r for r in rows[1:]}
    assert set(by) == {"schuler_mean", "lavrov", "transit", "fit"}
    assert by["fit"]["mean_sigma_rad"] == pytest.approx(by["fit"]["crlb_rad"], rel=0.01)
    assert abs(by["fit"]["floor_rad"]) < 0.01 * by["fit"]["crlb_rad"]


def test_scatter_sigma_is_the_matrix_form_without_the_matrices():
    """σ̂_a² = |P B a|² / tr(BᵀPB) (means.scatter_sigma's definition) evaluated without forming B (k × ν)
    or BᵀPB (ν × ν): equal to the dense form to round-off (the dense form's own cancellation with
    readings of 0.3 rad and a scatter of 1e-4 rad is ~eps·0.3/1e-4 ≈ 7e-13 relative; measured ≤ 1e-12),
    and a day of a fast swing (2e5 reversal points, whose dense BᵀPB would be 320 GB) costs O(ν)."""
    import math

    from gyro_instrument.estimators.north.means import scatter_sigma
    rng = np.random.default_rng(5)
    for nu in (4, 5, 9, 64, 257):
        a = 0.3 + 1e-4 * rng.normal(size=nu)
        k = nu - 2
        B = np.zeros((k, nu))
        for j in range(k):
            B[j, j:j + 3] = [0.25, 0.5, 0.25]
        P = np.eye(k) - 1.0 / k
        r = P @ B @ a
        dense = math.sqrt(float(r @ r) / float(np.trace(B.T @ P @ B)))
        got, dof = scatter_sigma(a)
        assert dof == nu - 3 and abs(got / dense - 1) < 1e-11, nu
    big = 0.3 + 1e-4 * rng.normal(size=200_000)
    got, dof = scatter_sigma(big)
    # independent readings of σ 1e-4: each triple mean has σ √(3/8) 1e-4 and σ̂ recovers 1e-4 within 1 %
    assert dof == 199_997 and abs(got / 1e-4 - 1) < 0.01


def test_transit_method_memory_is_linear_in_the_record():
    """The transit σ's gradient is accumulated in one vector of the transits' size: a record of 2000
    transits (20 000 s read at 2 Hz, 0.64 MB of readings) peaks at ~4.4 MB traced (measured), where
    one gradient vector per run of three transits (the form before) held 2000 × 2000 doubles (32 MB,
    twice with their mean) — a 48 h estimate of quet_gyroscopes peaked at 2.5 GB through it. Bound
    12 MB: the linear cost with room for numpy's temporaries, far below the quadratic 64 MB. The
    centre stays within 5σ of the truth (σ 2.8e-7 rad here)."""
    import tracemalloc
    t, u = record(duration=20000.0, rate=2.0, seed=1)
    tracemalloc.start()
    try:
        est = north.transit_method(t, u, CENTRE + 0.002, SIGMA)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 12e6, peak
    assert abs(est.centre_rad - CENTRE) < 5 * est.sigma_rad
