"""Issue 38: ``plot --out`` into a directory it cannot write ended in a 29-line OSError traceback
after drawing; it is now refused before anything is read or drawn: exit 2, one line naming the
path, nothing created. And a read-only HOME: matplotlib's two-line complaint (and a new font cache
every run) replaced by one note and a private temporary MPLCONFIGDIR kept between runs."""

import os

import pytest

from gyro_instrument.cli import main as core_main
from machine_env import cli, needs_mount_ns, run_readonly


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    d = tmp_path_factory.mktemp("plot_ro")
    assert core_main(["simulate", "quet_paris", "--duration-s", "30", "--out", str(d / "q.csv"), "--quiet"]) == 0
    return d / "q.csv"


@needs_mount_ns
def test_plot_out_in_a_read_only_directory_is_one_line_exit_2(table, tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    for out in (ro, ro / "views" / "deeper"):   # the directory itself, and one that would be made inside it
        r = run_readonly(cli("plot", table, "--out", out), [ro], text=True)
        assert r.returncode == 2, r.stderr
        lines = r.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"gyro-instrument: error: --out = '{out}' is invalid: is not "
                                                       "writable"), lines
        if out != ro:
            assert lines[0].endswith(f"(nor can it be created in {ro})")
    assert list(ro.iterdir()) == []


def test_plot_out_under_a_file_is_one_line_exit_2(table, tmp_path, capsys):
    # a path below a regular file: no directory can be made there (ENOTDIR), whoever runs it
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert core_main(["plot", str(table), "--out", str(blocker / "views")]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and f"--out = '{blocker / 'views'}' is invalid: {blocker} is not a directory" in err[0], err


@needs_mount_ns
def test_plot_with_a_read_only_home_uses_a_private_matplotlib_directory(table, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("MPLCONFIGDIR", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")}
    env |= {"HOME": str(home), "TMPDIR": str(tmp_path / "tmp")}
    (tmp_path / "tmp").mkdir()
    r = run_readonly(cli("plot", table, "--out", tmp_path / "views"), [home], env, text=True)
    assert r.returncode == 0, r.stderr
    private = tmp_path / "tmp" / f"gyro_instrument-matplotlib-{os.getuid()}"
    notes = [ln for ln in r.stderr.splitlines() if "matplotlib" in ln.lower()]
    assert notes == [f"gyro-instrument: note: matplotlib's directories under HOME are not writable: using {private} "
                     "(MPLCONFIGDIR)"], r.stderr
    assert sorted(p.name for p in (tmp_path / "views").iterdir()) == ["angles.png", "bob_path.png", "swing_azimuth.png"]
    assert any(private.glob("fontlist-*.json"))      # matplotlib's font cache, found again by the next run
