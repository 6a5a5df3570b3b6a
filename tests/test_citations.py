"""Shipped files cite what a reader can find (issue 36): no path of a development machine (a home
or work directory, a sibling ``../shared`` checkout) in the package, its documentation or its
sample bags. The tests and CI scripts may read ``../shared/realdata`` at run time (it lies beside
the clone); what ships must cite the paper, manual or page itself."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Where a path points at one machine's files: a home or work directory, a mount, a drive letter, a
#: sibling checkout. System paths a program reads on any Linux machine (/proc, /sys, /dev, /tmp,
#: /etc, /usr) are not citations and are not matched.
MACHINE_PATH = re.compile(r"(?<![\w.])(/(?:work|home|Users|root|mnt|media|scratch)/[\w.~-]"
                          r"|\.\./shared\b|~/[\w.-]+/|\b[A-Z]:\\{1,2}\w)")

SHIPPED = ("gyro_instrument", "docs", "msg_docs", "bags", "README.md", "package.xml", "setup.py", "setup.cfg")


def _shipped_text_files():
    for top in SHIPPED:
        path = ROOT / top
        for f in ([path] if path.is_file() else sorted(path.rglob("*"))):
            if f.is_file() and "__pycache__" not in f.parts:
                data = f.read_bytes()
                if b"\0" not in data[:8192]:        # text, not an .mcap or an image
                    yield f, data.decode("utf-8", errors="replace")


def test_the_pattern_finds_what_it_is_for():
    # one real case each (the gyrotheodolite scene's old citation among them), and system paths not
    for bad in ("/work/shared/physics_notes.md", "see /home/ann/notes.txt", "../shared/seeds/x.txt",
                "~/projects/gyro/", r"C:\Users\x", r"C:\\Users\\x"):
        assert MACHINE_PATH.search(bad), bad
    for fine in ("/proc/meminfo", "/sys/fs/cgroup/memory.max", "/dev/null", "/tmp", "/etc/hosts",
                 "/<gyro>/heading", "/static_transforms", "https://example.org/work/x", "rosbag2_2024/home/"):
        assert not MACHINE_PATH.search(fine), fine


def test_no_shipped_file_cites_a_machine_path():
    found = []
    for f, text in _shipped_text_files():
        for n, line in enumerate(text.splitlines(), start=1):
            m = MACHINE_PATH.search(line)
            if m:
                found.append(f"{f.relative_to(ROOT)}:{n}: {line.strip()[:100]}")
    assert not found, "cite the published source instead:\n" + "\n".join(found)
