"""benchmarks/report.py, which writes docs/performance.md: every section it names is a benchmark of the folder,
every section of the page is one of them, and a section is replaced in place (or added) without touching the rest."""

import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("report", ROOT / "benchmarks" / "report.py")
report = importlib.util.module_from_spec(spec)
spec.loader.exec_module(report)


def test_sections_are_the_benchmarks_and_the_page_has_no_other():
    assert all((ROOT / "benchmarks" / name).is_file() for name in report.SECTIONS)
    text = report.DOCS.read_text()
    begun = re.findall(r"<!-- (\S+): begin -->", text)
    assert begun == re.findall(r"<!-- (\S+): end -->", text) and len(set(begun)) == len(begun)
    assert set(begun) <= set(report.SECTIONS)
    for name in begun:   # each says how it was made and how to make it again
        block = text[text.index(f"<!-- {name}: begin -->"):text.index(f"<!-- {name}: end -->")]
        assert f"report.py {name}" in block or f"benchmarks/{name}" in block


def test_write_replaces_one_section_in_place_and_adds_a_new_one_at_the_end():
    a, b = report.markers("bench_pn.py"), report.markers("bench_ode.py")
    text = f"# Performance\n\nintro\n\n## PN\n\n{a[0]}\nold pn\n{a[1]}\n\n## ODE\n\n{b[0]}\nold ode\n{b[1]}\n"
    replaced = report.write(text, "bench_pn.py", ["new", "pn"])
    assert replaced == text.replace("old pn", "new\npn")
    added = report.write(replaced, "bench_many.py", ["many"])
    assert added.startswith(replaced.rstrip("\n"))
    assert added.endswith(f"## {report.SECTIONS['bench_many.py'].title}\n\n<!-- bench_many.py: begin -->\nmany\n"
                          "<!-- bench_many.py: end -->\n")


def test_unknown_benchmark_is_refused(capsys):
    import pytest

    with pytest.raises(SystemExit) as exit_:
        report.main(["bench_nothing.py"])
    assert exit_.value.code == 2 and "unknown benchmark bench_nothing.py" in capsys.readouterr().err
