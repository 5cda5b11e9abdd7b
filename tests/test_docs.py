"""The documentation site builds with warnings as errors (docstrings included), and every gallery example runs in
the build (sphinx-gallery stops at an example that raises).  The site is built from a copy of docs/ and examples/ in
a temporary folder, so the build writes nothing into the repository."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

from helpers import needs

ROOT = Path(__file__).resolve().parents[1]


@needs("sphinx", "furo", "myst_parser", "sphinx_gallery", "matplotlib", "pycbc", "lalsimulation")
def test_site_builds_with_warnings_as_errors_and_runs_every_example(tmp_path):
    for folder in ("docs", "examples"):
        shutil.copytree(ROOT / folder, tmp_path / folder, ignore=shutil.ignore_patterns("_build", "auto_examples"))
    html = tmp_path / "html"
    build = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", "-d", str(tmp_path / "doctrees"),
                            str(tmp_path / "docs"), str(html)], capture_output=True, text=True, timeout=600)
    assert build.returncode == 0, build.stderr[-4000:]
    examples = sorted(path.stem for path in (ROOT / "examples").glob("plot_*.py"))
    assert len(examples) == 6
    for name in examples:
        page = (html / "auto_examples" / f"{name}.html").read_text()
        assert re.search(rf'src="../_images/sphx_glr_{name}_\d+\.png"', page), f"{name} drew no figure"
    api = (html / "api.html").read_text()
    for name in ("pnrotor.pn.evolve", "pnrotor.pn.evolve_many", "pnrotor.waveform.modes.Modes",
                 "pnrotor.waveform.stream.polarizations", "pnrotor.hdf5.write", "pnrotor.hdf5.read", "pnrotor.batch.run",
                 "pnrotor.interop.gwsignal.PNRotorGenerator", "pnrotor.interop.lal.spintaylor_orbit"):
        assert f'id="{name}"' in api, f"{name} is not in the API reference"
    assert "|θ|" in api   # bars of magnitudes are text, not substitutions (docs/conf.py)
    for page in ("guide/frames", "guide/accuracy", "hdf5-schema", "architecture", "physics", "pipelines", "performance"):
        assert (html / f"{page}.html").is_file()
