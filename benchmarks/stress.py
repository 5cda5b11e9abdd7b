"""The stress table (README, "Stress and stability"): every case of benchmarks/stress_numerics.py
(the angular-velocity integrators at their corners) and benchmarks/stress_pn.py (post-Newtonian
extremes and a random-binary sweep), run in one go and printed as one Markdown table.

Each row: the area, the case, how many runs were tried, how many crashed (an uncaught exception,
non-finite output or a missing termination reason; the goal is 0), the outcome (statuses or
termination reasons seen), the worst error measured and how it grows.

    python benchmarks/stress.py [--quick] [--only numerics|pn] [-o TABLE.md]
"""

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import stress_numerics  # noqa: E402
import stress_pn  # noqa: E402

SECTIONS = {"numerics": stress_numerics, "pn": stress_pn}
COLUMNS = ("area", "case", "tried", "crashes", "outcome", "worst_error", "growth")


def cell(value):
    if value is None:
        return "—"
    if isinstance(value, float):
        return f"{value:.2e}"
    return str(value).replace("|", "\\|")


def markdown(rows):
    lines = ["| " + " | ".join(COLUMNS).replace("_", " ") + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(cell(row[c]) for c in COLUMNS) + " |" for row in rows]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="long runs to T = 10⁶ instead of 10⁷, backward runs over 10⁵ instead of 10⁶, 100 random "
                        "binaries instead of 5000")
    parser.add_argument("--only", choices=sorted(SECTIONS), help="run one section")
    parser.add_argument("-o", "--output", metavar="TABLE.md", help="also write the table to this file")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    rows = []
    for name, module in SECTIONS.items():
        if args.only in (None, name):
            for row in module.cases(quick=args.quick):
                rows.append(row)
                print(f"  [{time.perf_counter() - start:7.1f} s] {row['area']}: {row['case']}", file=sys.stderr)
    crashes = sum(row["crashes"] for row in rows)
    tried = sum(row["tried"] for row in rows)
    text = (markdown(rows) + f"\n\n{len(rows)} cases, {tried} runs, {crashes} crashes, "
            f"{time.perf_counter() - start:.0f} s{' (--quick)' if args.quick else ''}\n")
    print(text)
    if args.output:
        Path(args.output).write_text(text)
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
