"""The text table of ``gyro-instrument typetest`` (:mod:`gyro_instrument.bench.typetest`)."""

import sys


def value_text(row) -> str:
    """A row's figure with its unit ('not measured' for null)."""
    if row["value"] is None:
        return "not measured"
    return f"{row['value']:.3f} {row['unit']}"


def print_typetest(rows, stream=None) -> None:
    """One block per compass: a line per (latitude, test) with the figure, its limit, PASS/FAIL and the
    clause; the note (the reason of a FAIL without a figure, the conditions) on the next line; then the
    IMO figures beside ISO's, once per test, and a count of FAILs."""
    out = stream or sys.stdout
    for name in dict.fromkeys(r["instrument"] for r in rows):
        mine = [r for r in rows if r["instrument"] == name]
        fails = sum(not r["pass"] for r in mine)
        print(f"type test of {name} (ISO 22090-1 sections 6.2-6.9 against 5.2-5.3): {len(mine) - fails} PASS, "
              f"{fails} FAIL", file=out)
        print(f"  {'lat deg':>8}  {'test':<21} {'value':>14} {'limit':>12}  result  clause", file=out)
        for r in mine:
            print(f"  {r['latitude_deg']:8.2f}  {r['name']:<21} {value_text(r):>14} {r['limit']:>8.3f} {r['unit']:<3}"
                  f"  {'PASS' if r['pass'] else 'FAIL':<6}  {r['clause']}", file=out)
            if r["note"] and (not r["pass"] or r["value"] is None):
                print(f"  {'':8}  {'':21} note: {r['note']}", file=out)
        print("  IMO figures beside ISO's:", file=out)
        for test, imo in dict.fromkeys((r["name"], r["imo"]) for r in mine):
            print(f"    {test:<21} {imo}", file=out)
