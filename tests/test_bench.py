"""``gyro-instrument bench --quick`` writes its CSVs and summary; the studies measure physics:
DOP853's azimuth error falls with the tolerance and the fit beats Quet's counting by orders of
magnitude at every observation time."""

import csv

from gyro_instrument.cli import main


def test_bench_quick_writes_studies(tmp_path, capsys):
    out = tmp_path / "bench"
    assert main(["bench", "--quick", "--out", str(out)]) == 0
    for name in ("work_precision.csv", "targets.csv", "observation_time.csv", "summary.md"):
        assert (out / name).exists(), name
    wp = [r for r in csv.DictReader(open(out / "work_precision.csv")) if r["method"].startswith("DOP853")]
    errs = [float(r["azimuth_error_rad"]) for r in sorted(wp, key=lambda r: -float(r["rtol"]))]
    assert errs == sorted(errs, reverse=True) and errs[-1] < 1e-9
    for r in csv.DictReader(open(out / "observation_time.csv")):
        assert float(r["rms_counting_deg"]) > 100 * float(r["rms_fit_deg"])
