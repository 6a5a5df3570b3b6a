"""Field books as surveyors write them (issue 33 item 5 and its bad input).

Angles as printed (DMS in four spellings, DD.MMSS, gon, scale divisions), times as clocks, ';' with
decimal commas, missed readings, outliers, the tape from the book (undamped periods, exact relation)
or from the scene, and the answer in the surveyor's units.
"""

import json
import math

import numpy as np
import pytest

from gyro_instrument.cli import main
from gyro_instrument.cli.parser import BOOK_TIME_UNITS
from gyro_instrument.cli.text import north_lines
from gyro_instrument.core.angle_formats import format_angle, parse_ddmmss, parse_dms
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.north import field_book as fb
from gyro_instrument.estimators import north
from gyro_instrument.estimators.north.field_book_read import TIME_UNITS

ARCSEC = math.pi / 648000.0
#: a damped swing's turning points about 180°10' (arcsec from 180°): c + d(−q)^k, q = 0.97 per swing
CENTRE_S, D_S, Q = 600.0, 3600.0, 0.97


def _turning(n=10, centre_s=CENTRE_S, d_s=D_S, q=Q):
    k = np.arange(n)
    return 180 * 3600 + centre_s + d_s * (-q) ** k           # arcsec


def _dms(arcsec, style):
    d, rest = divmod(round(arcsec * 10), 36000)
    m, s10 = divmod(rest, 600)
    s = f"{s10 // 10:02d}.{s10 % 10}"
    return {"sym": f"{d}°{m:02d}'{s}\"", "dot": f"{d}.{m:02d}.{s10 // 10:02d}.{s10 % 10}", "space": f"{d} {m:02d} {s}",
            "dash": f"{d}-{m:02d}-{s}", "ddmmss": f"{d}.{m:02d}{s10 // 10:02d}{s10 % 10}"}[style]


def _book(tmp_path, text, name="b.csv"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return str(p)


# ----------------------------------------------------------------------------- the written forms
def test_dms_spellings_and_ddmmss_are_the_same_angle():
    want = 179 + 1 / 60 + 56.5 / 3600
    for s in ("179°01'56.5\"", "179°01′56.5″", "179.01.56.5", "179 01 56.5", "179-01-56.5", "179:01:56.5"):
        assert parse_dms(s) == pytest.approx(want, abs=1e-12), s
    assert parse_dms("-0°01'56\"") == pytest.approx(-(1 / 60 + 56 / 3600), abs=1e-15)
    assert parse_ddmmss("179.01565") == pytest.approx(want, abs=1e-12)      # read as text, not via a float
    assert parse_ddmmss("179.1") == pytest.approx(179 + 10 / 60, abs=1e-12)   # 179.1 = 179°10'
    for bad in ("179.5", "179 61 00", "179°01'60\"", "abc"):
        with pytest.raises(ValueError):
            parse_dms(bad)


def test_formats_wrap_after_rounding():
    """A reading a hair below 360° rounds to 360 and wraps: never "360°00′00.0″" nor "360.000000°"."""
    assert format_angle(359.99999999, "dms") == "0°00′00.0″"
    assert format_angle(359.99999999, "deg") == "0.000000°"
    assert format_angle(359.999999999, "gon") == "0.00000 gon"
    assert format_angle(180 + 10 / 60 + 6.6 / 3600, "dms") == "180°10′06.6″"
    assert format_angle(90.0, "gon") == "100.00000 gon"


@pytest.mark.parametrize("style, unit", [("sym", "dms"), ("dot", "dms"), ("space", "dms"), ("dash", "dms"),
                                         ("ddmmss", "ddmmss")])
def test_a_book_in_each_spelling_reduces_as_in_degrees(tmp_path, style, unit):
    a = _turning()
    deg = _book(tmp_path, "reading_deg\n" + "\n".join(repr(float(x) / 3600) for x in np.round(a, 1)) + "\n", "deg.csv")
    sep = ";" if style == "dash" else ","                  # '-' spelled cells in a ';' book, for variety
    body = "\n".join(f"{_dms(x, style)}" for x in a)
    path = _book(tmp_path, f"reading_{unit}{sep}remark\n" + body.replace("\n", f"{sep}\n") + f"{sep}\n")
    got, ref = fb.field_book_north(fb.read_field_book(path)), fb.field_book_north(fb.read_field_book(deg))
    for k in ("schuler_mean", "lavrov"):
        # the same readings to 0.1" (both written to 0.1"): equal to float round-off
        assert got[k].centre_rad == pytest.approx(ref[k].centre_rad, abs=1e-12)


def test_ddmmss_is_never_guessed_from_a_decimal_column(tmp_path):
    rows = "\n".join(["179.0156", "181.1726", "179.0605", "181.1259"])
    dd = fb.read_field_book(_book(tmp_path, "reading_ddmmss\n" + rows, "a.csv")).readings_rad
    deg = fb.read_field_book(_book(tmp_path, "reading_deg\n" + rows, "b.csv")).readings_rad
    assert math.degrees(dd[0]) == pytest.approx(179 + 1 / 60 + 56 / 3600, abs=1e-12)
    assert math.degrees(deg[0]) == pytest.approx(179.0156, abs=1e-12)
    with pytest.raises(SceneError, match=r"line 2, column reading_dms: '179.0156' is a decimal number"):
        fb.read_field_book(_book(tmp_path, "reading_dms\n" + rows, "c.csv"))


def test_semicolons_decimal_commas_clock_times_and_the_separator_option(tmp_path):
    text = "time_hms;reading_gon\n10:00:00;199,9\n10:04:00;200,3\n10:08:00,5;199,92\n10:12:00;200,28\n"
    book = fb.read_field_book(_book(tmp_path, text))
    assert book.times_s == pytest.approx([36000, 36240, 36480.5, 36720])
    assert book.readings_rad / (math.pi / 200) == pytest.approx([199.9, 200.3, 199.92, 200.28], abs=1e-12)
    assert any("decimal commas" in n for n in book.notes)
    mmss = fb.read_field_book(_book(tmp_path, "time,reading_deg\n0:00,1\n4:01.5,-1\n8:03,1\n", "m.csv"))
    assert mmss.times_s == pytest.approx([0, 241.5, 483]) and mmss.time_unit == "hms"
    with pytest.raises(SceneError, match="column 'time_hms;reading_gon' is not a field-book column"):
        fb.read_field_book(_book(tmp_path, text), separator=",")
    assert set(BOOK_TIME_UNITS) == set(TIME_UNITS)          # --time-unit offers what a header takes


def test_scale_divisions_with_their_stated_value(tmp_path, capsys):
    path = _book(tmp_path, "reading_div\n12.5\n-10.25\n11.75\n-9.5\n")
    assert main(["estimate", "--reversal-points", path, "--json"]) == 2
    assert "--scale-division" in capsys.readouterr().err
    assert main(["estimate", "--reversal-points", path, "--scale-division", "10arcmin", "--json"]) == 0
    n = json.loads(capsys.readouterr().out)["north"]
    c = north.schuler_mean(np.array([12.5, -10.25, 11.75, -9.5]) * 10 / 60).centre_rad      # degrees
    assert n["north_reading_deg"] == pytest.approx(c % 360, abs=1e-12)


# ----------------------------------------------------------------------------- missed points, outliers
def test_a_missed_reading_is_left_out_in_its_place(tmp_path):
    """Noise-free geometric turning points (Lavrov's model, exact): with turning point 4 missing (its time
    written) Lavrov's fit at the points' numbers still gives the centre to round-off, and the Schuler mean
    of the complete triples stays within its second-order damping bias (schuler_bias: d(1-q)^2/(4(1+q))
    per triple, < 1.2" here)."""
    a = _turning(12)
    rows = [f"{60 * k},{'' if k == 3 else repr(float(x) / 3600)}" for k, x in enumerate(a)]
    book = fb.read_field_book(_book(tmp_path, "time_s,reading_deg\n" + "\n".join(rows) + "\n"))
    assert book.on.index.tolist() == [0, 1, 2, 4, 5, 6, 7, 8, 9, 10, 11]
    assert book.on.missed == ({"turning_point": 4, "line": 5, "time_s": 180.0},)
    est = fb.field_book_north(book)
    centre = math.radians((180 * 3600 + CENTRE_S) / 3600)
    assert est["lavrov"].centre_rad == pytest.approx(centre, abs=1e-12)
    assert abs(est["schuler_mean"].centre_rad - centre) < 1.2 * ARCSEC
    assert fb.half_period(book.on)[0] == pytest.approx(60.0, rel=1e-12)          # the missed point's time counts


def test_an_outlier_is_named_and_noise_rarely_is(tmp_path):
    rng = np.random.default_rng(7)
    a = _turning(16) + rng.normal(0, 2.0, 16)               # 2" reading noise
    a[9] += 40.0                                            # 20 sigma
    path = _book(tmp_path, "reading_deg\n" + "\n".join(repr(float(x) / 3600) for x in a) + "\n")
    book = fb.read_field_book(path)
    found = fb.outliers(book.on, fb.field_book_north(book)["schuler_mean"].centre_rad)
    assert [(o["turning_point"], o["line"]) for o in found] == [(10, 11)] and found[0]["sigmas"] > 10
    # noise only: the test's false-alarm rate (documented 1-2 % per book, fb.outliers) over 300 books of 16
    # points; binomial at 2 %: mean 6, sd 2.4, so <= 16 is 4 sd
    alarms = 0
    for _ in range(300):
        sw = fb.Swing("r", np.arange(16), (_turning(16) + rng.normal(0, 2.0, 16)) * ARCSEC, np.arange(16) + 2,
                      tuple("x" * 16), np.array([], dtype=int), np.array([]))
        alarms += bool(fb.outliers(sw, north.schuler_mean(sw.readings_rad).centre_rad))
    assert alarms <= 16


# ----------------------------------------------------------------------------- the tape
def test_the_tape_from_the_book_is_exact_for_damped_swings(tmp_path):
    """Turning points of the exact model: the rotor-off swing ü = −(D_B/A)(u − Z) − 2δ u̇ and the rotor-on
    swing about its equilibrium c, D_K sin(c − N) = D_B (Z − c), with ω_on² = (D_K cos(c − N) + D_B)/A
    (small swings: each a damped cosine, turning points exactly geometric and π/ω_d apart). Lavrov's
    centre, the undamped periods and N = c − atan(x (Z − c)) recover N to round-off; the damped periods
    with the linear law would be off by arcseconds (δ²/ω² of 0.2 % and 0.6 % in the two periods)."""
    N, Z = math.radians(180.0), math.radians(180.0 + 2.0)            # a tape zero 2° from north
    kK, kB, d_on, d_off = 4.0e-4, 4.0e-5, 1.0e-3, 5.0e-4               # D_K/A, D_B/A (s^-2), δ (1/s)
    from scipy.optimize import brentq
    c = brentq(lambda x: kK * math.sin(x - N) - kB * (Z - x), N - 0.1, N + 0.1)
    w_on, w_off = math.sqrt(kK * math.cos(c - N) + kB - d_on ** 2), math.sqrt(kB - d_off ** 2)
    T_on, T_off = math.pi / w_on, math.pi / w_off
    q_on, q_off = math.exp(-d_on * T_on), math.exp(-d_off * T_off)
    on = [c + 0.01 * (-q_on) ** k for k in range(8)]
    off = [Z + 0.01 * (-q_off) ** k for k in range(5)]
    rows = [",".join([repr(T_on * k), repr(math.degrees(on[k])),
                      repr(T_off * k) if k < 5 else "", repr(math.degrees(off[k])) if k < 5 else ""]) for k in range(8)]
    book = fb.read_field_book(_book(tmp_path, "time_s,reading_deg,tape_time_s,tape_reading_deg\n" + "\n".join(rows)))
    ests, tape, _ = fb.reduce_field_book(book)
    assert ests["lavrov"].centre_rad == pytest.approx(N, abs=1e-10)
    assert tape["ratio_db_dk"] == pytest.approx(kB / (kK * math.cos(c - N)), rel=1e-9)
    linear_damped = c + T_on ** 2 / (T_off ** 2 - T_on ** 2) * (c - Z)
    assert abs(linear_damped - N) > 1.0 * ARCSEC


@pytest.fixture(scope="module")
def gyrotheodolite_book(tmp_path_factory):
    """The shipped gyrotheodolite's rotor-on turning points (noise on, seed 3) as a field book without tape
    readings, clockwise readings (−angle), with times."""
    from gyro_instrument.estimators.pipeline import measure, simulate_truth
    from gyro_instrument.scenes import load_scene
    from gyro_instrument.sensors import SensorModel
    scene = load_scene("gyrotheodolite")
    rec = measure(scene, simulate_truth(scene), 3)["gak1"]
    rp = north.reversal_points(rec["t"], -rec["angle"], SensorModel.from_scene(scene).effective_sigma_rad())
    path = tmp_path_factory.mktemp("gt") / "book.csv"
    fb.write_field_book(path, rp.readings_rad, rp.times_s, angle_unit="deg")
    return str(path)


def test_a_book_without_tape_readings_takes_the_scenes_tape_and_says_so(gyrotheodolite_book, capsys):
    assert main(["estimate", "--reversal-points", gyrotheodolite_book, "--scene", "gyrotheodolite", "--json"]) == 0
    n = json.loads(capsys.readouterr().out)["north"]
    assert n["tape"]["source"].startswith("the scene's tape") and n["tape"]["ratio_db_dk"] == pytest.approx(0.1)
    err = ((n["mount_azimuth_deg"] - 359.75 + 180) % 360 - 180) * 3600
    # the scene's mount 359.75°: within 4 sigma of the Schuler mean (the scatter's sigma)
    assert abs(err) < 4 * n["sigma_arcsec"]
    assert main(["estimate", "--reversal-points", gyrotheodolite_book]) == 0
    raw = " ".join(capsys.readouterr().out.split())
    assert "raw: no tape in the book and no scene" in raw
    assert main(["estimate", "--reversal-points", gyrotheodolite_book, "--scene", "gyrotheodolite"]) == 0
    assert "tape removed (the scene's tape (gak1)" in " ".join(capsys.readouterr().out.split())


# ----------------------------------------------------------------------------- bad input, one line, exit 2
@pytest.mark.parametrize("text, extra, words", [
    ("reading_dms\n179 01 56\n181 17 26\n", (), "holds 2 turning point readings"),
    ("reading_dms\n179 01 56\n181 17 26\n181 20 00\n", (), "line 4, column reading_dms: '181 20 00': turning "
                                                           "points must alternate"),
    ("time_s,reading_deg\n0,1\n10,-1\n5,1\n", (), "line 4, column time_s: '5' must be later"),
    ("reading_dms\n179 01 56\n181 17 26\n179 06 05\n", ("--angle-unit", "deg"), "--angle-unit = 'deg' is invalid: "
                                                                                "contradicts the header"),
    ("reading\n1\n-1\n1\n", ("--angle-unit", "gon", "--scene", "quet_gyroscopes", "--set", "site.latitude_deg=90"),
     "site.latitude_deg = 90"),
    ("reading_deg,side\n1,left\n-1,right\n1,left\n", (), "line 2, column side: 'left' disagrees"),
    ("reading_deg\n1\n-1\n1\n", ("--set", "site.latitude_deg=10"), "--set"),
])
def test_bad_books_exit_2_with_one_line_naming_it(tmp_path, capsys, text, extra, words):
    assert main(["estimate", "--reversal-points", _book(tmp_path, text), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and words in err and "Traceback" not in err


def test_every_header_unit_is_an_option_unit(tmp_path, capsys):
    """--angle-unit takes the units the errors advise (gon, dms, ...), for a bare reading column."""
    for unit, cells in (("gon", "199.9\n200.3\n199.92\n"), ("dms", "179 01 56\n181 17 26\n179 06 05\n")):
        assert main(["estimate", "--reversal-points", _book(tmp_path, "reading\n" + cells), "--angle-unit", unit,
                     "--json"]) == 0
        capsys.readouterr()


def test_north_lines_render_bias_flags_and_pre_orientation_when_present():
    m = {"mount_azimuth_deg": 359.9999999999, "sigma_arcsec": 1.5, "n_used": 9, "needs": "x",
         "bias_arcsec": 0.6, "bias_flagged": True}
    block = {"instrument": "g", "mount_azimuth_deg": 45.5, "sigma_arcsec": 0.4, "crlb_arcsec": 0.38,
             "methods": {"schuler_mean": m}, "pre_orientation": {"centre_from_north_deg": 5.0}}
    text = "\n".join(north_lines(block, "dms"))
    assert "45°30′00.0″ +/- 0.4\"" in text and "0°00′00.0″" in text and "360°" not in text
    assert "bias 0.6\" [FLAGGED" in text and "pre-orientation: centre_from_north_deg 5" in text
    assert "FLAGGED" not in "\n".join(north_lines(block | {"methods": {"s": m | {"bias_flagged": False}}}))
    assert "50.55556 gon" in "\n".join(north_lines(block, "gon"))


def test_plot_draws_a_field_book(tmp_path, monkeypatch):
    """plot of a book (a reading column): one view, field_book.png, with a missed point and a tape. The
    figure draws the book's values: the turning points at their times (minutes), as arcminutes from
    north (so their differences are the readings' differences x 60), the tape's likewise, and the
    missed point marked at its time (10 min)."""
    pytest.importorskip("matplotlib")
    import matplotlib.image as mpimg
    from matplotlib.figure import Figure
    drawn, save = {}, Figure.savefig

    def savefig(fig, path, *args, **kwargs):
        drawn.update({ln.get_label(): (np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float))
                      for ax in fig.axes for ln in ax.lines})
        return save(fig, path, *args, **kwargs)
    monkeypatch.setattr(Figure, "savefig", savefig)
    a = _turning(9)
    rows = [f"{150 * k},{'' if k == 4 else repr(float(x) / 3600)},{400 * k if k < 4 else ''},"
            f"{repr(180.5 + 0.1 * (-0.9) ** k) if k < 4 else ''}" for k, x in enumerate(a)]
    path = _book(tmp_path, "time_s,reading_deg,tape_time_s,tape_reading_deg\n" + "\n".join(rows) + "\n")
    out = tmp_path / "views"
    assert main(["plot", path, "--out", str(out)]) == 0
    assert [p.name for p in out.iterdir()] == ["field_book.png"]
    h, w, _ = mpimg.imread(out / "field_book.png").shape
    assert h > 200 and w >= 1600
    k = np.array([0, 1, 2, 3, 5, 6, 7, 8])                                  # point 4 missed
    t_min, y_arcmin = drawn["turning points (rotor on)"]
    np.testing.assert_allclose(t_min, 150 * k / 60, rtol=0, atol=1e-12)
    np.testing.assert_allclose(y_arcmin - y_arcmin[0], (a[k] - a[0]) / 60, rtol=0, atol=1e-9)
    t_min, y_arcmin = drawn["tape turning points (rotor off)"]
    tape = 180.5 + 0.1 * (-0.9) ** np.arange(4)
    np.testing.assert_allclose(t_min, 400 * np.arange(4) / 60, rtol=0, atol=1e-12)
    np.testing.assert_allclose(y_arcmin - y_arcmin[0], (tape - tape[0]) * 60, rtol=0, atol=1e-9)
    assert any(np.array_equal(x, [10.0, 10.0]) for x, _ in drawn.values())  # the missed point's mark
    assert main(["plot", path, "--out", str(out)]) == 2                     # already there: --overwrite


def test_angle_format_applies_to_a_simulated_estimates_north(capsys, monkeypatch):
    """--angle-format reaches the north lines of 'estimate SCENE' too (print_estimate), not only field books."""
    from gyro_instrument.cli import text
    block = {"instrument": "g", "mount_azimuth_deg": 359.75, "sigma_arcsec": 0.4, "crlb_arcsec": 0.38, "methods": {}}
    assert text.estimate_headline({"north": block, "latitude_deg": None}, "dms")[0].startswith(
        "north: scale zero of g at azimuth 359°45′00.0″ +/- 0.4\"")


def test_tape_readings_without_times_are_said_not_removed(tmp_path, capsys):
    path = _book(tmp_path, "time_s,reading_deg,tape_reading_deg\n0,1,0.2\n60,-1,-0.2\n120,0.9,0.19\n180,-0.9,\n")
    assert main(["estimate", "--reversal-points", path]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "the tape's pull is NOT removed" in out and "note: tape readings without the times of both swings" in out
