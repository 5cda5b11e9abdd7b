"""pnrotor.Options: the one place of the model and integration options' names, defaults and checks, shared by evolve,
evolve_many, stream, batch tables and the CLI; the keywords of the same names keep working and give bitwise the same
runs."""

import dataclasses
import inspect
import subprocess
import sys

import numpy as np
import pytest

import pnrotor
from pnrotor import Options, options as options_module
from pnrotor.pn.evolve import OPTIONS, check_inputs

BINARY = (30.0, 10.0, (0.5, 0.1, 0.3), (0.0, 0.4, -0.2), 20.0)
CHANGED = dict(approximant="TaylorT5", pn_order=3, spin_orbit_order=2.5, atol=1e-10, max_steps=500_000,
               precession="averaged_varpi")


def same(a, b):
    for name in ("t", "v", "Phi", "chi1", "chi2", "R", "ell_hat"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert a.inputs == b.inputs and a.termination == b.termination


def test_options_give_bitwise_the_run_of_the_same_keywords():
    """options=Options(**k) and the keywords k give the same run, bitwise; a keyword replaces the field of options;
    the defaults are Options()."""
    by_keywords = pnrotor.evolve(*BINARY, f_max=60.0, **CHANGED)
    same(pnrotor.evolve(*BINARY, f_max=60.0, options=Options(**CHANGED)), by_keywords)
    same(pnrotor.evolve(*BINARY, f_max=60.0, options=Options(**{**CHANGED, "pn_order": 2}), pn_order=3), by_keywords)
    same(pnrotor.evolve(*BINARY, f_max=60.0, options=Options()), pnrotor.evolve(*BINARY, f_max=60.0))
    assert by_keywords.inputs["approximant"] == "T5" and by_keywords.inputs["spin_spin_order"] == 3.0


def test_evolve_many_and_stream_take_options_as_evolve():
    m1, m2, c1, c2, f = BINARY
    keywords = dict(CHANGED, horizon_absorption=True)
    a = pnrotor.evolve_many([m1, 12.0], [m2, 8.0], [c1, c1], [c2, c2], f, f_end=60.0, **keywords)
    b = pnrotor.evolve_many([m1, 12.0], [m2, 8.0], [c1, c1], [c2, c2], f, f_end=60.0, options=Options(**keywords))
    for name in ("v", "Phi", "chi1", "chi2", "R", "ell_hat"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.inputs.keys() == b.inputs.keys() and a.inputs["approximant"] == b.inputs["approximant"] == "TaylorT5"
    run = pnrotor.evolve(*BINARY, f_max=60.0, sampling=1 / 1024, **CHANGED)
    streamed = pnrotor.stream(*BINARY, f_max=60.0, delta_t=1 / 1024, options=Options(**CHANGED))
    assert streamed.inputs == run.inputs


@pytest.mark.parametrize("field, value, said", [
    ("approximant", "T9", "approximant must be one of T1, T4, T5"),
    ("pn_order", 5.0, r"pn_order must be a multiple of 0.5 in \[0.0, 4.5\]"),
    ("spin_orbit_order", 4.5, r"spin_orbit_order must be a multiple of 0.5 in \[-1.0, 4.0\]"),
    ("spin_spin_order", 0.25, r"spin_spin_order must be a multiple of 0.5 in \[-1.0, 3.0\]"),
    ("atol", 0.0, "atol must be > 0"),
    ("rtol", -1.0, "rtol >= 0"),
    ("rotor", "inertial", "rotor must be 'coprecessing' or 'orbital'"),
    ("precession_phase_shift", 1, "precession_phase_shift must be None"),
    ("integrate_rotor", "yes", "integrate_rotor must be True or False"),
    ("precession", "exact", "precession must be 'averaged', 'averaged_varpi' or 'instantaneous'"),
    ("max_steps", 0, "max_steps must be an integer from 1"),
    ("tidal_order", 4, "tidal_order must be 0"),
    ("horizon_absorption", 1, "horizon_absorption must be True or False"),
])
def test_a_bad_option_is_refused_when_made_naming_it(field, value, said):
    """Options checks each field when made (and replace() again), with the message evolve gives for that keyword."""
    with pytest.raises(ValueError, match=said):
        Options(**{field: value})
    with pytest.raises(ValueError, match=said):
        dataclasses.replace(Options(), **{field: value})
    with pytest.raises(ValueError, match=said):
        pnrotor.evolve(*BINARY, **{field: value})


def test_unknown_keywords_and_wrong_options_are_type_errors():
    for call in (pnrotor.evolve, pnrotor.evolve_many):
        with pytest.raises(TypeError, match=rf"{call.__name__}\(\) got an unexpected keyword argument 'pn_ordre'"):
            call(*BINARY, pn_ordre=3)
        with pytest.raises(TypeError, match="options must be a pnrotor.Options, got dict"):
            call(*BINARY, options={"pn_order": 3})
    with pytest.raises(TypeError, match="unexpected keyword argument 'sampling'"):
        pnrotor.stream(*BINARY, delta_t=1 / 1024, sampling="steps")
    with pytest.raises(TypeError, match="stream\\(\\) got an unexpected keyword argument 'pn_ordre'"):
        pnrotor.stream(*BINARY, delta_t=1 / 1024, pn_ordre=3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        Options().pn_order = 3


def test_resolved_defaults():
    """The defaults a run uses follow from the fields: spin orders min(pn_order, 4) and min(pn_order, 3), the phase
    shift at spin-orbit order >= 3, 'instantaneous' on the orbital rotor without it, tidal order 6."""
    r = dict(zip(options_module.OPTION_DEFAULTS, Options(pn_order=2.5, approximant="spintaylort1").resolved))
    assert (r["approximant"], r["spin_orbit_order"], r["spin_spin_order"], r["precession_phase_shift"],
            r["tidal_order"]) == ("T1", 2.5, 2.5, False, 6.0)
    r = dict(zip(options_module.OPTION_DEFAULTS, Options(precession="instantaneous").resolved))
    assert (r["rotor"], r["precession_phase_shift"], r["spin_orbit_order"], r["spin_spin_order"]) == (
        "orbital", False, 3.5, 3.0)


def test_one_place_for_names_and_defaults():
    """The keyword defaults evolve, evolve_many and stream share with each other, the fields of Options and the batch
    table's defaults agree; pipelines pass the fields through by name."""
    from pnrotor.interop.pipelines import evolve_options
    many = inspect.signature(pnrotor.evolve_many).parameters
    for name in ("ell_hat", "n_hat", "kappa1", "kappa2", "lambda1", "lambda2", "options"):
        assert many[name].default == OPTIONS[name], name
    for name, default in options_module.DEFAULTS.items():
        expected = getattr(Options(), name) if name in options_module.OPTION_DEFAULTS else OPTIONS[name]
        assert default == expected, name
    assert set(options_module.TABLE_OPTIONS) <= set(options_module.OPTION_DEFAULTS)
    assert {"pn_order", "atol", "max_steps", "kappa1"} <= evolve_options()
    assert "options" not in evolve_options() and "approximant" not in evolve_options()


def test_options_and_the_cli_help_load_no_numba():
    """The CLI's parser reads the names, defaults and ranges without numpy or numba (its cold-start promise); making
    an Options loads numpy, not numba."""
    code = ("import sys, pnrotor.options; from pnrotor.cli import build_parser; build_parser(); "
            "assert not {'numpy', 'numba'} & set(sys.modules); o = pnrotor.Options(pn_order=2); "
            "assert 'numba' not in sys.modules; print(o.resolved[1])")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout == "2.0\n", done.stderr


def test_keywords_made_once_stay_apart_by_type_and_sign():
    """The Options of repeated keywords are made once (options_of's cache), keyed by type and repr too: True then 1
    still refuses 1; 3 and 3.0, 0.0 and -0.0 keep what was given, whatever came before; an unhashable value is checked
    without the cache."""
    of = options_module.options_of
    assert of(None, {"integrate_rotor": True}, "evolve") is of(None, {"integrate_rotor": True}, "evolve")
    for first, second in ((-0.0, 0.0), (0.0, -0.0)):
        of(None, {"rtol": first}, "evolve")
        assert str(of(None, {"rtol": second}, "evolve").rtol) == str(second)
    with pytest.raises(ValueError, match="integrate_rotor must be True or False, got 1"):
        of(None, {"integrate_rotor": 1}, "evolve")
    assert type(of(None, {"pn_order": 3.0}, "evolve").pn_order) is float
    assert type(of(None, {"pn_order": 3}, "evolve").pn_order) is int
    with pytest.raises(ValueError, match="pn_order must be a multiple of 0.5"):
        of(None, {"pn_order": [3.0]}, "evolve")


def test_a_registry_change_reaches_options_made_before():
    """An approximant name resolved by an Options made earlier is resolved anew after the registry changes."""
    from pnrotor import approximants
    from pnrotor.pn import vdot
    of = options_module.options_of
    approximants.register(approximants.Approximant("TX", vdot.taylor_t4, "T4 under another name", aliases=("Foo",)))
    try:
        assert of(None, {"approximant": "foo"}, "evolve").resolved[0] == "TX"
    finally:
        approximants.unregister("TX")
    with pytest.raises(ValueError, match="approximant must be one of"):
        of(None, {"approximant": "foo"}, "evolve")
    with pytest.raises(ValueError, match="approximant must be one of"):
        check_inputs(*BINARY, approximant="foo")


def test_the_internal_caller_name_is_no_keyword():
    """evolve, stream and evolve_many name themselves in errors; that name is not a keyword a user can set, and a
    missing binary input is said before a bad option, as before Options."""
    with pytest.raises(TypeError, match=r"evolve\(\) got an unexpected keyword argument 'caller'"):
        pnrotor.evolve(*BINARY, caller="x")
    with pytest.raises(TypeError, match=r"stream\(\) got an unexpected keyword argument 'caller'"):
        pnrotor.stream(*BINARY, delta_t=1 / 1024, caller="x")
    with pytest.raises(TypeError, match="evolve_many\\(\\) missing m2"):
        pnrotor.evolve_many(30.0, pn_order=9)


def test_settings_hold_the_checked_options_in_their_order():
    """Settings are built with the Checked options spread by position: their fields from ``approximant`` on are
    Checked's, which are Options' and then the sampling."""
    from pnrotor.pn.settings import Checked, Settings
    names = [field.name for field in dataclasses.fields(Settings)]
    start = names.index("approximant")
    assert tuple(names[start:start + len(Checked._fields)]) == Checked._fields
    assert Checked._fields == (*options_module.OPTION_DEFAULTS, "sampling", "sampling_value")
