"""The README's promises: every ```python example runs as written (in order, one namespace, in a fresh folder with
a `waveforms/` folder, as after the install), the main job's command runs, and the test command is what `.ci/run`
runs."""

import re
import shlex
from pathlib import Path

import pytest
from helpers import needs

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def blocks(language):
    return re.findall(rf"^```{language}\n(.*?)^```", README, flags=re.S | re.M)


def test_readme_is_short():
    assert len(README.splitlines()) <= 200  # a user guide's entry, not a log (#34)


@needs("distributed", "pycbc")   # the Dask batch and the PyCBC examples
def test_every_python_example_runs(tmp_path, monkeypatch):
    examples = blocks("python")
    assert len(examples) >= 7  # evolve, modes, verify, population, Dask batch, h5py, PyCBC
    monkeypatch.chdir(tmp_path)
    (tmp_path / "waveforms").mkdir()
    namespace = {}
    for k, code in enumerate(examples):
        exec(compile(code, f"README.md python example {k + 1}", "exec"), namespace)
    # what the examples print and claim, checked against what they computed
    assert namespace["run"].termination == "energy_balance" and namespace["outcome"].written == 2
    assert namespace["hp"].sample_times[-1] == 0.0 and len(namespace["hp"]) == len(namespace["t"])
    assert (tmp_path / "waveforms" / "run.h5").is_file() and (tmp_path / "waveforms" / "batch.h5").is_file()


def commands():
    return [line for line in (block.strip() for block in blocks("")) if line.startswith("python3 -m pip install -e")]


def test_test_command_is_what_ci_runs():
    install, test = commands()[1].split(" && ")
    ci = (ROOT / ".ci" / "run").read_text()
    assert f"{install.replace('pip install', 'pip install -q')} || exit 1" in ci  # -q: quieter, the same install
    assert re.search(rf"^PNROTOR_REQUIRE_REFERENCES=1 {re.escape(test)}$", ci, flags=re.M)


def test_main_job_command_runs(tmp_path, monkeypatch, capsys):
    from pnrotor import hdf5
    from pnrotor.cli import main

    install, job = commands()[0].split(" && ")
    assert install == "python3 -m pip install -e ." and job.startswith("pnrotor evolve ")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "waveforms").mkdir()
    assert main(shlex.split(job)[1:]) == 0
    written = re.search(r"^wrote (\S+)$", capsys.readouterr().out, flags=re.M).group(1)
    run = hdf5.read(written)
    assert written.startswith("waveforms/") and run.termination == "energy_balance"
    assert run.inputs["f_ref_Hz"] == pytest.approx(20.0)
