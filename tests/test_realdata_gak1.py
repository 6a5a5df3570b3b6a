"""A published GAK1 field book, read as printed (issue 33 item 6).

Williams & Belling 1967 (Tijdschrift voor Kadaster en Landmeetkunde, table p. 273; ../shared/realdata/
README.md): twenty consecutive turning points of a Wild GAK1 no. 3139 on a Wild T2 at Johannesburg,
circle readings in degrees-minutes-seconds as printed, with ``turning_point`` and ``side`` columns; no
times and no tape readings, so the raw reduction. The printed means beside the table are the triple
means (a_k + 2 a_(k+1) + a_(k+2))/4 rounded to whole arcseconds; the paper's weighted mean is
180°10'06" (its +10'46" is an instrument constant applied afterwards, not part of the reduction).
"""

import csv
import json
import math
import os

import pytest

from gyro_instrument.cli import main
from gyro_instrument.core.angle_formats import parse_dms

from realdata import REALDATA  # noqa: E402

BOOK = os.path.join(REALDATA, "williams_belling_1967_gak1.csv")
MEANS = os.path.join(REALDATA, "williams_belling_1967_printed_means.csv")


def _printed_means():
    with open(MEANS, encoding="utf-8") as fh:
        rows = [r for r in csv.reader(line for line in fh if not line.startswith("#"))][1:]
    return {int(r[0]): parse_dms(r[1]) for r in rows}


def _estimate(capsys, *extra):
    assert main(["estimate", "--reversal-points", BOOK, "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)["north"]


@pytest.mark.parametrize("scene", [(), ("--scene", "quet_gyroscopes", "--set", "site.latitude_deg=-26.2")])
def test_the_printed_means_and_the_papers_mean(capsys, scene):
    """Without a scene, and on a scene without a tape at Johannesburg's 26.2° S (quet_gyroscopes' horizontal
    gyroscope has none), the reduction is the raw one and the same."""
    n = _estimate(capsys, *scene)
    assert n["tape"] is None and n["reduction"].startswith("raw")
    assert n["turning_points"] == 20 and n["missed"] == []
    triples = n["methods"]["schuler_mean"]["triple_means"]
    printed = _printed_means()
    assert len(printed) == 14
    for k, deg in printed.items():
        t = triples[k - 1]
        assert t["turning_points"] == [k, k + 1, k + 2]
        # the printed means are rounded to whole seconds: a quarter-second mean is at most 0.5" from them
        # (0.5" exactly for x.5"; 1e-6" for the floating point)
        assert abs(t["mean_deg"] - deg) * 3600 <= 0.5 + 1e-6, (k, t["mean_dms"])
    # the Schuler mean of the 20 points: 180°10'06.6"; the paper prints 180°10'06" (rounded to 1", so
    # +-0.5", and a weighted mean whose weights it does not print, perhaps over more of its 45 points): 1"
    # is 0.12 of this mean's sigma from the scatter (8.6")
    assert abs(n["north_reading_deg"] - parse_dms("180°10'06\"")) * 3600 < 1.0
    assert n["north_reading_dms"] == "180°10′06.6″"
    assert n["mount_azimuth_deg"] == pytest.approx(360.0 - n["north_reading_deg"], abs=1e-12)
    assert n["mount_azimuth_gon"] == pytest.approx(n["mount_azimuth_deg"] / 0.9, abs=1e-9)
    # the means range over nearly a minute (the paper): 180°09'48" to 180°10'50" printed
    spread = max(t["mean_deg"] for t in triples) - min(t["mean_deg"] for t in triples)
    assert 55 < spread * 3600 < 65


def test_the_early_swings_are_named(capsys):
    """Independent reading of the raw values: on each side, a reading less the mean of the readings two
    before and two after is 107" at turning point 5 and -128" at 6, at most 41" elsewhere (the swing's
    settling that the paper is about). The book names those two, keeps them, and only them."""
    n = _estimate(capsys)
    named = {o["turning_point"]: o for o in n["outliers"]}
    assert sorted(named) == [5, 6]
    assert named[5]["line"] == 12 and named[5]["reading"] == "179°11'16\""
    assert named[6]["reading"] == "181°07'43\"" and named[6]["sigmas"] < 0
    assert n["turning_points"] == 20                      # kept


def test_the_book_in_the_surveyors_units_on_the_text_output(capsys):
    assert main(["estimate", "--reversal-points", BOOK, "--angle-format", "dms"]) == 0
    out = " ".join(capsys.readouterr().out.split())          # the text is wrapped at 100 columns
    assert "at azimuth 179°49′53.4″" in out and "north reads 180°10′06.6″ on the circle" in out
    assert "outlier: turning point 5, line 12" in out and "raw" in out
