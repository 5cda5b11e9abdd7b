"""Result types check their own invariants (issue #36, item 1): a malformed `Evolution` or `Modes` is a
ValueError before a compiled kernel reads it, a malformed `FrameHistory` or `Population` when it is built, each
with the problems `pnrotor.hdf5.write` names for the same object; never a crash of the process.

The cases that crashed run in a child process (before the fix `pnrotor.modes` died of SIGSEGV on two of them),
as does every example of the fuzz test, so that a crash fails the test instead of ending the test run."""

import dataclasses
import json
import os
import pickle
import signal
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pnrotor
from pnrotor import hdf5

SPINS = dict(chi1=(0.5, 0.3, 0.2), chi2=(0.0, -0.4, 0.3))


@pytest.fixture(scope="module")
def precessing():
    return pnrotor.evolve(30, 10, SPINS["chi1"], SPINS["chi2"], 20, sampling=1 / 512)


@pytest.fixture(scope="module")
def aligned():
    return pnrotor.evolve(30, 10, (0, 0, 0.3), (0, 0, -0.2), 20, sampling=1 / 512)


def write_problems(run, tmp_path):
    """The ValueError of hdf5.write for `run`, without its 'cannot write this KIND: ' prefix."""
    with pytest.raises(ValueError) as error:
        hdf5.write(tmp_path / "x.h5", run)
    return str(error.value).split(": ", 1)[1]


CRASHES = """
import dataclasses, json, numpy as np, pnrotor
run = pnrotor.evolve(30, 10, (0.5, 0.3, 0.2), (0.0, -0.4, 0.3), 20, sampling=1 / 512)
R0 = run.R.copy(); R0[5] = 0.0
cases = {
    "R transposed": dict(R=run.R.T.copy()),
    "chi of one row": dict(chi1=run.chi1[:1].copy(), chi2=run.chi2[:1].copy()),
    "R of 3 columns": dict(R=run.R[:, :3].copy()),
    "chi2 of half length": dict(chi2=run.chi2[: len(run) // 2].copy()),
    "Phi of half length": dict(Phi=run.Phi[: len(run) // 2].copy()),
    "v a list": dict(v=list(run.v[:100])),
    "a zero rotor": dict(R=R0),
    "no inputs": dict(inputs={}),
}
out = {}
for name, change in cases.items():
    try:
        pnrotor.modes(dataclasses.replace(run, **change))
        out[name] = "no error"
    except Exception as e:
        out[name] = f"{type(e).__name__}: {e}"
print(json.dumps(out))
"""


def test_modes_of_a_malformed_evolution_is_a_value_error_not_a_crash(precessing, tmp_path):
    done = subprocess.run([sys.executable, "-c", CRASHES], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"the process ended with {done.returncode}: {done.stderr[-2000:]}"
    out = json.loads(done.stdout)
    n = len(precessing)
    expected = {
        "R transposed": f"dataset 'R' has shape (4, {n}), expected ({n}, 4)",
        "chi of one row": f"dataset 'chi1' has shape (1, 3), expected ({n}, 3)",
        "R of 3 columns": f"dataset 'R' has shape ({n}, 3), expected ({n}, 4)",
        "chi2 of half length": f"dataset 'chi2' has shape ({n // 2}, 3), expected ({n}, 3)",
        "Phi of half length": f"dataset 'Phi' has shape ({n // 2},), expected ({n},)",
        "v a list": "dataset 'v' is list",
        "a zero rotor": "dataset 'R' has 1 row of zero or extreme norm (not a rotor: |R|^2 must be a normal float64), the first "
                        "at index 5",
        "no inputs": "group 'inputs' lacks 'm1_Msun', 'm2_Msun'",
    }
    for name, text in expected.items():
        assert out[name].startswith("ValueError: cannot compute the modes of this Evolution: "), (name, out[name])
        assert text in out[name], (name, out[name])
    # the same problems as hdf5.write names for the same object
    change = dict(R=precessing.R.T.copy())
    message = out["R transposed"].split("Evolution: ", 1)[1]
    assert message == write_problems(dataclasses.replace(precessing, **change), tmp_path)


def test_modes_checks_the_evolution_as_it_is_now(aligned):
    run = dataclasses.replace(aligned)
    run.v = run.v[:10]   # changed after it was built
    with pytest.raises(ValueError, match=r"dataset 'v' has shape \(10,\)"):
        pnrotor.modes(run)


@pytest.mark.parametrize("run", ["precessing", "aligned"])
def test_rotors_of_any_norm_the_kernels_handle_give_the_same_modes_the_others_an_error(run, request):
    """A rotor stands for the same rotation at any norm (v' = R v R^-1): the modes of rotors scaled by 1e-150 or
    1e150 are those of the unit rotors; |R|^2 beyond float64's normal range (a ZeroDivisionError or NaN modes
    before) is refused."""
    run = request.getfixturevalue(run)
    reference = pnrotor.modes(run, ell_max=4).data
    for scale in (1e-150, 3.0, 1e150):
        data = pnrotor.modes(dataclasses.replace(run, R=run.R * scale), ell_max=4).data
        assert np.abs(data - reference).max() < 1e-14 * np.abs(reference).max()
    for scale in (1e-160, 1e160, 0.0):
        with pytest.raises(ValueError, match=f"dataset 'R' has {len(run)} rows of zero or extreme norm"):
            pnrotor.modes(dataclasses.replace(run, R=run.R * scale))


def test_a_malformed_modes_is_a_value_error_before_rotating_or_projecting(precessing, tmp_path):
    m = pnrotor.modes(precessing, ell_max=3)
    n = len(precessing)
    cases = {
        "data": (dict(data=m.data[:, :-1].copy()), f"dataset 'data' has shape (12, {n - 1}), expected (12, {n})"),
        "R": (dict(R=m.R[::2].copy()), "dataset 'R' has shape"),
        "Phi": (dict(Phi=m.Phi[:3].copy()), "dataset 'Phi' has shape (3,)"),
        "ell_max": (dict(ell_max=4), f"dataset 'data' has shape (12, {n}), expected (21, {n})"),
        "inputs": (dict(inputs={}), "group 'inputs' lacks 'M_seconds', 'ell_max'"),
        "frame": (dict(frame="sideways"), "frame 'sideways' is not one of inertial, coprecessing, coorbital"),
    }
    for name, (change, text) in cases.items():
        bad = dataclasses.replace(m, **change)
        for call, doing in ((lambda: bad.polarizations(0.3), "cannot compute the polarizations of"),
                            (lambda: bad.in_frame("coorbital"), "cannot rotate")):
            with pytest.raises(ValueError) as error:
                call()
            assert str(error.value).startswith(f"{doing} this Modes: "), (name, str(error.value))
            assert text in str(error.value), (name, str(error.value))
        if name != "frame":
            assert str(error.value).split(": ", 1)[1] == write_problems(bad, tmp_path), name


def test_a_frame_history_and_a_population_are_checked_when_built(tmp_path):
    from pnrotor.history import FrameHistory

    good = dict(t=np.linspace(0.0, 1.0, 5), R=np.tile([1.0, 0.0, 0.0, 0.0], (5, 1)), formulation="rotor",
                method="DOP853", atol=1e-10, rtol=0.0, nfev=1, nsteps=1, naccepted=1, nrejected=0, n_resets=0,
                status=0, message="ok", wall_time=0.0)
    history = FrameHistory(**good)
    with pytest.raises(ValueError, match=r"^cannot build this FrameHistory: dataset 'R' has shape \(4, 5\)"):
        dataclasses.replace(history, R=history.R.T.copy())
    with pytest.raises(ValueError, match=r"attribute 'nfev' is float 1.5, expected an integer"):
        FrameHistory(**dict(good, nfev=1.5))

    population = pnrotor.evolve_many([30, 20, 1e9], 10, SPINS["chi1"], SPINS["chi2"], 20, frequencies=[25, 30])
    assert population.R.shape == (3, 2, 4) and population.termination[2, 0] == "invalid"   # NaN rows allowed
    for change, text in ((dict(v=population.v[:2]), r"dataset 'v' has shape \(2, 2\), expected \(3, 2\)"),
                         (dict(chi1=population.chi1[:, 0]), r"dataset 'chi1' has shape \(3, 3\), expected \(3, 2, 3\)"),
                         (dict(nsteps=population.nsteps.astype(float)), "dataset 'nsteps' is float64, expected int64"),
                         (dict(termination=population.termination.astype(str)), "dataset 'termination' is a str"),
                         (dict(R=population.R * 0), r"dataset 'R' has 4 rows of zero or extreme norm \(not a rotor: "
                                                     r"\|R\|\^2 must be a normal float64\), the first at index \(0, 0\)")):
        with pytest.raises(ValueError, match="^cannot build this Population: " + text):
            dataclasses.replace(population, **change)
    single = pnrotor.evolve_many([30, 20], 10, SPINS["chi1"], SPINS["chi2"], 20, f_end=30)
    with pytest.raises(ValueError, match=r"dataset 'Phi' has shape \(2, 1\), expected \(2,\)"):
        dataclasses.replace(single, Phi=single.Phi[:, None])


# --------------------------------------------------------------------------------------------------
# fuzz: malformed result objects passed to modes / polarizations / in_frame / hdf5.write, each example in a
# forked child, so that a crash (a signal) is a failing example that hypothesis can shrink
# --------------------------------------------------------------------------------------------------

def in_child(calls, timeout=60.0):
    """Run each of `calls` in a forked child, in order; the outcome of each: 'ok', or 'TYPE: message' for an
    exception; or the signal or exit status that ended the child."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:   # the child: never returns into pytest
        os.close(read)
        outcomes = []
        for call in calls:
            try:
                call()
                outcomes.append("ok")
            except Exception as error:   # noqa: BLE001 — reported to the parent, which judges it
                outcomes.append(f"{type(error).__name__}: {str(error)[:300]}")
        os.write(write, pickle.dumps(outcomes))
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as pipe:
        data = pipe.read()   # until the child exits (its end closes)
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        return f"killed by {signal.Signals(os.WTERMSIG(status)).name}"
    return pickle.loads(data) if data else f"exit status {os.waitstatus_to_exitcode(status)}"


def _with_value(a, value, index):
    """A copy of array `a` with `value` at its flat `index` (modulo its size), an object array unless `a` holds
    floats."""
    b = np.array(a, copy=True)
    if b.dtype.kind not in "fc":
        b = b.astype(object)
    if b.size:
        b.flat[index % b.size] = value
    return b


ARRAY_CHANGES = {
    "transposed": lambda a, i: np.asarray(a).T.copy(),
    "half": lambda a, i: a[: len(a) // 2],
    "one row": lambda a, i: a[:1],
    "empty": lambda a, i: a[:0],
    "one more": lambda a, i: np.concatenate([a, a[:1]]),
    "last column dropped": lambda a, i: a[..., :-1],
    "flattened": lambda a, i: np.asarray(a).reshape(-1),
    "extra axis": lambda a, i: np.asarray(a)[None],
    "float32": lambda a, i: np.asarray(a).astype(np.float32),
    "int64": lambda a, i: np.asarray(a).astype(np.int64),
    "complex": lambda a, i: np.asarray(a).astype(np.complex128),
    "object": lambda a, i: np.asarray(a).astype(object),
    "bool": lambda a, i: np.asarray(a).astype(bool),
    "list": lambda a, i: np.asarray(a).tolist(),
    "scalar": lambda a, i: np.float64(1.0),
    "None": lambda a, i: None,
    "text": lambda a, i: "text",
    "NaN": lambda a, i: _with_value(a, np.nan, i),
    "inf": lambda a, i: _with_value(a, -np.inf, i),
    "zeros": lambda a, i: np.zeros(np.shape(a)),
    "a zero": lambda a, i: _with_value(a, 0.0, i),
    "huge": lambda a, i: _with_value(a, 1e300, i),
    "tiny": lambda a, i: a * 1e-320 if a.dtype.kind in "fc" else a,
    "Fortran order": lambda a, i: np.asfortranarray(a),
    "big-endian": lambda a, i: np.asarray(a).astype(np.asarray(a).dtype.newbyteorder(">")),
    "strided": lambda a, i: np.repeat(np.asarray(a), 2, axis=0)[::2],
}
OTHER_VALUES = [None, 1.5, -3, 0, 100, True, "x", "inertial", "precessing", np.float64(2.0), [1.0], {}, np.zeros(2)]


@st.composite
def changes(draw, run):
    """1 to 3 changes of fields of `run`: an array changed (ARRAY_CHANGES), a dict losing a key or replaced, or
    another field given another value."""
    out = {}
    for _ in range(draw(st.integers(1, 3))):
        field = draw(st.sampled_from([f.name for f in dataclasses.fields(run) if f.name != "dense"]))
        value = out.get(field, getattr(run, field))
        if isinstance(value, np.ndarray):
            how = draw(st.sampled_from(sorted(ARRAY_CHANGES)))
            out[field] = ARRAY_CHANGES[how](value, draw(st.integers(0, 10 ** 6)))
        elif isinstance(value, dict) and value and draw(st.booleans()):
            key = draw(st.sampled_from(sorted(value)))
            out[field] = {k: v for k, v in value.items() if k != key}
        else:
            out[field] = draw(st.sampled_from(OTHER_VALUES))
    return out


CLEAR = ("ok", "ValueError: ", "TypeError: ")


@pytest.fixture(scope="module")
def results(precessing, aligned):
    from pnrotor.history import FrameHistory

    history = FrameHistory(t=np.linspace(0.0, 1.0, 7), R=np.tile([0.5, 0.5, 0.5, 0.5], (7, 1)), formulation="rotor",
                           method="DOP853", atol=1e-10, rtol=0.0, nfev=1, nsteps=1, naccepted=1, nrejected=0,
                           n_resets=0, status=0, message="ok", wall_time=0.0, inputs={"omega": "test"})
    population = pnrotor.evolve_many([30, 20], 10, SPINS["chi1"], SPINS["chi2"], 20, frequencies=[25, 30])
    return {"precessing": precessing, "aligned": aligned, "modes": pnrotor.modes(precessing, ell_max=3),
            "history": history, "population": population}


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_malformed_results_are_clear_errors_never_a_crash(results, tmp_path_factory, data):
    name = data.draw(st.sampled_from(sorted(results)), label="result")
    run = results[name]
    change = data.draw(changes(run), label="change")
    path = tmp_path_factory.mktemp("fuzz") / "run.h5"
    if name in ("history", "population"):   # checked when built
        calls = [lambda: dataclasses.replace(run, **change)]
        bad = run
    else:
        bad = dataclasses.replace(run, **change)
        calls = [lambda: hdf5.write(path, bad)]
        if name == "modes":
            calls += [lambda: bad.polarizations(0.3, 0.1), lambda: bad.in_frame("coorbital")]
        else:
            calls += [lambda: pnrotor.modes(bad, ell_max=4).polarizations(0.3)]
    outcomes = in_child(calls)
    assert isinstance(outcomes, list), f"{name} with {sorted(change)}: the child was {outcomes}"
    for outcome in outcomes:
        assert outcome.startswith(CLEAR), f"{name} with {sorted(change)}: {outcome}"
