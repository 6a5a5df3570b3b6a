"""Shipped files cite what a reader can find (issue 36): no path of a development machine (a home
or work directory, a sibling ``../shared`` checkout) in the package, its documentation or its
sample bags. The tests and CI scripts may read ``../shared/realdata`` at run time (it lies beside
the clone); what ships must cite the paper, manual or page itself. Nor may any shipped file, the
tests included, cite the development notes by name (:data:`FORBIDDEN_NOTES`)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Where a path points at one machine's files: a home or work directory, a mount, a drive letter, a
#: sibling checkout. System paths a program reads on any Linux machine (/proc, /sys, /dev, /tmp,
#: /etc, /usr) are not citations and are not matched.
MACHINE_PATH = re.compile(r"(?<![\w.])(/(?:work|home|Users|root|mnt|media|scratch)/[\w.~-]"
                          r"|\.\./shared\b|~/[\w.-]+/|\b[A-Z]:\\{1,2}\w)")

SHIPPED = ("gyro_instrument", "docs", "msg_docs", "bags", "README.md", "package.xml", "setup.py", "setup.cfg")

#: The development machine's working notes (``../shared/*.md``). A reader of the package cannot
#: open them: they summarise the papers, standards and manuals that a citation must name instead
#: (Quet 1853, Puiseux 1852, REP-103/145, ISO 22090-1, a manual by title: docs/physics.md,
#: "Sources"), and where a note states this project's own result the code derives it in a docstring
#: or a test. Each name with its reason:
FORBIDDEN_NOTES = {
    "physics_notes": "a summary of Quet 1853 and Puiseux 1852: cite the paper's section and equation",
    "gyrocompass_sources": "a list of the standards and manuals: cite the standard's clause or the manual",
    "ros_notes": "notes on ROS 2/rosbag2: cite the REP or the rosbag2 source file",
    "shared/architecture": "the layering's intent: docs/architecture.md is the shipped page",
}
#: Checked in everything that ships, in the tests (whose comments give a number's source) and tools.
NOTE_CHECKED = SHIPPED + ("tests", "tools")


def _cited_notes(line):
    """The forbidden note names a line cites (case-insensitive: ``Physics_Notes.md`` too)."""
    low = line.lower()
    return [name for name in FORBIDDEN_NOTES if name in low]


def _shipped_text_files(tops=SHIPPED):
    for top in tops:
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


def test_the_note_names_are_found_as_the_old_citations_wrote_them():
    # one old citation of each note (as they stood before issue 36), and published names not
    for bad in ("(physics_notes 'Estimation')", "gyrocompass_sources.md §1a", "ros_notes says breadth-first",
                "(shared/architecture.md)", "PHYSICS_NOTES.md"):
        assert _cited_notes(bad), bad
    for fine in ("Quet 1853 sec. 4 §1 eq. 9", "docs/architecture.md", "ISO 22090-1 §5.3.4", "REP-145",
                 "docs/physics.md, Sources"):
        assert not _cited_notes(fine), fine


def test_no_shipped_file_or_test_cites_the_development_notes():
    this = Path(__file__).resolve()
    found = []
    for f, text in _shipped_text_files(NOTE_CHECKED):
        if f.resolve() == this:                     # the list of forbidden names itself
            continue
        for n, line in enumerate(text.splitlines(), start=1):
            for name in _cited_notes(line):
                found.append(f"{f.relative_to(ROOT)}:{n}: {name} ({FORBIDDEN_NOTES[name]}): {line.strip()[:80]}")
    assert not found, "cite the published source the note points to:\n" + "\n".join(found)
