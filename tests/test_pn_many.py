"""pnrotor.pn.evolve_many against single evolve calls: bitwise the same end states, binary by binary."""

import math

import astropy.units as u
import numba
import numpy as np
import pytest

from pnrotor.pn import evolve, evolve_many

FIELDS = ("v", "Phi", "chi1", "chi2", "R", "ell_hat")


def _table(n, seed):
    """n binaries: nonspinning, aligned and precessing, mass ratios 1–8, some ℓ̂ tilted."""
    rng = np.random.default_rng(seed)
    m1 = rng.uniform(5.0, 40.0, n)
    m2 = m1 / rng.uniform(1.0, 8.0, n)
    c1 = rng.uniform(-0.6, 0.6, (n, 3))
    c2 = rng.uniform(-0.6, 0.6, (n, 3))
    c1[0::4] = c2[0::4] = 0.0                       # nonspinning
    c1[1::4, :2] = c2[1::4, :2] = 0.0               # aligned with ℓ̂ = ẑ
    ell = np.tile([0.0, 0.0, 1.0], (n, 1))
    ell[3::4] = [0.6, 0.0, 0.8]
    nh = np.tile([1.0, 0.0, 0.0], (n, 1))
    nh[3::4] = [0.8, 0.0, -0.6]
    return m1, m2, c1, c2, ell, nh


def _single_end(i, m1, m2, c1, c2, ell, nh, f_ref, f_end, options):
    """(t, state, termination, nfev of that half) of binary i from evolve, at the end evolve_many integrates to."""
    if f_end is not None and f_end < f_ref:
        e = evolve(m1[i], m2[i], c1[i], c2[i], f_ref, f_min=f_end, ell_hat=ell[i], n_hat=nh[i], sampling="steps",
                   **options)
        return e.t[0], [getattr(e, k)[0] for k in FIELDS], e.stats["termination_backward"], e.stats["nfev_backward"]
    e = evolve(m1[i], m2[i], c1[i], c2[i], f_ref, f_max=f_end, ell_hat=ell[i], n_hat=nh[i], sampling="final",
               **options)
    return e.t[-1], [getattr(e, k)[-1] for k in FIELDS], e.termination, e.stats["nfev"]


ENDS = {"v_max", "energy_balance", "vdot_nonpositive", "vdot_peak", "vdot_divergent"}
"""The terminations that end an inspiral (the others stop it early: max_steps, nonfinite, ...)."""


def _assert_same_state(pop, at, single, target):
    """Entry ``at`` of pop against a single run's (t, state, termination) where that run stopped: bitwise in
    ``stopped_at``; in the state fields too where the target was reached (termination f_max or f_min for a target
    frequency, an end of the inspiral without one), all NaN where it was not."""
    t, state, term = single[:3]
    reached = term in ("f_max", "f_min") if target is not None and not math.isnan(target) else term in ENDS
    assert pop.termination[at] == term and pop.reached[at] == reached and pop.stopped_at["t"][at] == t, at
    assert pop.t[at] == t if reached else math.isnan(pop.t[at]), at
    for k, x in zip(FIELDS, state):
        np.testing.assert_array_equal(pop.stopped_at[k][at], x, err_msg=f"entry {at}, {k}")
        np.testing.assert_array_equal(getattr(pop, k)[at], x if reached else np.full_like(x, np.nan),
                                      err_msg=f"entry {at}, {k}")


def _assert_same_as_single(pop, table, f_ref, f_end, options):
    m1, m2, c1, c2, ell, nh = table
    for i in range(m1.size):
        fe = None if f_end is None else float(np.broadcast_to(f_end, m1.shape)[i])
        single = _single_end(i, m1, m2, c1, c2, ell, nh, f_ref, fe, options)
        assert pop.nfev[i] == single[3], i
        _assert_same_state(pop, i, single, fe)


@pytest.mark.parametrize("options", [
    {},
    {"approximant": "T1", "rotor": "orbital", "atol": 1e-9},
    {"approximant": "T5", "precession": "instantaneous", "pn_order": 3.0},
    {"integrate_rotor": True, "kappa1": 3.0, "kappa2": 5.0},
])
def test_end_of_inspiral_equals_single_evolve(options):
    table = _table(12, 1)
    pop = evolve_many(*table[:4], 20.0, ell_hat=table[4], n_hat=table[5], **options)
    assert set(pop.termination) <= {"energy_balance", "vdot_peak", "vdot_divergent", "v_max"}
    _assert_same_as_single(pop, table, 20.0, None, options)


def test_forward_and_backward_targets_equal_single_evolve():
    """f_end per binary: above f_ref forward (f_max), below backward (f_min); the spins at the target."""
    table = _table(12, 2)
    f_end = np.where(np.arange(12) % 2 == 0, 12.0, 35.0)
    pop = evolve_many(*table[:4], 20.0, f_end=f_end, ell_hat=table[4], n_hat=table[5])
    assert list(pop.termination) == ["f_min" if f < 20 else "f_max" for f in f_end]
    _assert_same_as_single(pop, table, 20.0, f_end, {})
    np.testing.assert_allclose(pop.v ** 3 / (np.pi * (table[0] + table[1]) * 4.925490947641267e-06), f_end,
                               rtol=1e-9)
    assert np.all((pop.t < 0) == (f_end < 20.0))


def test_invalid_binaries_are_reported_not_raised():
    table = list(_table(6, 3))
    table[2][1] = [0.9, 0.9, 0.0]         # |χ₁| > 1
    m1 = table[0].copy()
    m1[4] = -3.0                           # negative mass
    first = evolve_many([-1.0, 30.0], [10.0, 10.0], [0, 0, 0], [0, 0, 0], 20.0)   # the first one too
    assert list(first.termination) == ["invalid", "energy_balance"] and "m1" in first.message[0]
    pop = evolve_many(m1, *table[1:4], [20.0, 20.0, 20.0, 20.0, 20.0, 5000.0], ell_hat=table[4], n_hat=table[5])
    assert list(pop.termination[[1, 4, 5]]) == ["invalid"] * 3
    assert "chi1" in pop.message[1] and "m1" in pop.message[4] and "f_ref" in pop.message[5]
    assert np.all(np.isnan(pop.R[[1, 4, 5]])) and np.all(pop.nfev[[1, 4, 5]] == 0)
    good = [0, 2, 3]
    assert not np.any(np.isnan(pop.R[good])) and "invalid" not in set(pop.termination[good])
    single = evolve(m1[2], table[1][2], table[2][2], table[3][2], 20.0, ell_hat=table[4][2], n_hat=table[5][2],
                    sampling="final")
    np.testing.assert_array_equal(pop.R[2], single.R[-1])


def test_results_do_not_depend_on_the_number_of_threads():
    """On two threads the integrations run eight halves at a time, as each thread is free; on one, all on the
    calling thread."""
    table = _table(40, 4)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = evolve_many(*table[:4], 20.0, ell_hat=table[4], n_hat=table[5])
    finally:
        numba.set_num_threads(before)
    many = evolve_many(*table[:4], 20.0, ell_hat=table[4], n_hat=table[5])
    for k in FIELDS + ("t", "nfev"):
        np.testing.assert_array_equal(getattr(one, k), getattr(many, k))


def test_every_half_is_integrated_once_on_two_threads(monkeypatch):
    """The threads take blocks of halves from one shared range: every half of a group is integrated exactly once
    (comparing outputs, as above, cannot see a half integrated twice)."""
    import threading
    import time

    from pnrotor import threads
    from pnrotor.pn import many

    real, blocks, names = many._integrate_all, {}, set()

    def loop(lo, hi, *args):
        blocks.setdefault(id(args[1]), (args[1], []))[1].append((lo, hi))   # args[1]: the group's Y0, kept alive
        names.add(threading.current_thread().name)
        real(lo, hi, *args)
        time.sleep(0.005)   # long enough a block that both threads take some

    loop.overloads = real.overloads
    monkeypatch.setattr(many, "_integrate_all", loop)
    monkeypatch.setattr(threads, "thread_count", lambda: 2)
    table = _table(60, 7)
    evolve_many(*table[:4], 20.0, ell_hat=table[4], n_hat=table[5])
    assert blocks and len(names) == 2
    for Y0, done in blocks.values():
        halves = [k for lo, hi in done for k in range(lo, hi)]
        assert sorted(halves) == list(range(Y0.shape[0])), (Y0.shape, done)


@pytest.mark.parametrize("call, match", [
    (lambda: evolve_many([], [], np.zeros((0, 3)), np.zeros((0, 3)), 20.0), "m1 has no binary"),
    (lambda: evolve_many([30, 20], [10, 10, 10], [0, 0, 0], [0, 0, 0], 20.0), "same length N .* got m1 2, m2 3"),
    (lambda: evolve_many([30, 20], [10, 10], np.zeros((3, 3)), [0, 0, 0], 20.0), "got m1 2, m2 2, chi1 3"),
    (lambda: evolve_many([True, 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0), "m1 must be numbers"),
    # a review of 2026-11-28: numbers as text were taken, as numpy converts them
    (lambda: evolve_many(["30", 30], [10, 10], [0, 0, 0], [0, 0, 0], 20.0), "m1 must be numbers"),
    (lambda: evolve_many(30, 10, [0, 0, 0], ["0", 0, 0], 20.0), "chi2 must be numbers"),
    (lambda: evolve_many(30, 10, [0, 0, 0], [0, 0, 0], np.array(["20"])), "f_ref must be numbers"),
    (lambda: evolve_many(30, 10, [0, 0, 0], [0, 0, 0], 20.0, frequencies=[b"50", 10]), "frequencies must be numbers"),
    (lambda: evolve_many(np.array([1, 0], bool), [10, 10], [0, 0, 0], [0, 0, 0], 20.0), "m1 must be numbers"),
    (lambda: evolve_many([30, 20], [10, 10], [0, 0, np.True_], [0, 0, 0], 20.0), "chi1 must be numbers"),
    (lambda: evolve_many(["abc", 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0), "m1 must be numbers"),
    (lambda: evolve_many([30, 20], [10, 10], [[0, 0, 0], [0, 0]], [0, 0, 0], 20.0), "chi1 must be numbers"),
    (lambda: evolve_many([[30], [20, 1]], [10, 10], [0, 0, 0], [0, 0, 0], 20.0), "m1 must be numbers"),
    # a review of 2026-11-27 (fifth session): (N, 1) spins were broadcast to (N, 3), complex masses ran as real,
    # Quantities of parameters without units lost them
    (lambda: evolve_many([30, 20], [10, 10], [[0.1], [0.2]], [0, 0, 0], 20.0), r"chi1 must have shape .* \(2, 1\)"),
    (lambda: evolve_many([30 + 1j, 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0), "m1 must be numbers"),
    (lambda: evolve_many([30, 20], 10, [0, 0, 0], [0, 0, 0], 20.0, kappa1=[1, 1, 1]), "got m1 2, kappa1 3"),
    (lambda: evolve_many([30, 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0, frequencies=np.ones((3, 2)) * 30),
     "got m1 2, m2 2, frequencies 3"),
    (lambda: evolve_many([30, 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0 * u.m), "f_ref must be numbers .* to Hz"),
    (lambda: evolve_many([30, 20] * u.one, 10, [0, 0, 0], [0, 0, 0], 20.0), "m1 must be .* in dimensionless"),
    (lambda: evolve_many([10 ** 400, 20], 10, [0, 0, 0], [0, 0, 0], 20.0), "m1 must be numbers"),
    (lambda: evolve_many([30, 20], 10, [0, 0, 0], [0, 0, 0], 20.0, f_end=10 ** 400), "f_end must be numbers"),
    (lambda: evolve_many([30, 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0, kappa1=1.0 * u.one),
     "kappa1 must be numbers, got an astropy Quantity"),
    (lambda: evolve_many([30, 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0, atol=-1.0), "atol"),
    (lambda: evolve_many([30, 20], [10, 10], [0, 0, 0], [0, 0, 0], 20.0, approximant="T3"), "approximant"),
])
def test_bad_shapes_and_shared_options_raise(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_evolve_many_calls_the_one_compiled_core(cold_python):
    """In a fresh process with an empty numba cache (so that the loop around the core is compiled, 15-50 s), evolve_many
    leaves the DOP853 core with its one signature: written as constants in the loop, the output mode and
    dense flag made numba compile (and cache) a second core.  And none of its kernels compiles numba's
    shape-mismatch error path (an array assignment such as N[i] = series: 5.4 s of string formatting in
    system._vdot_series_each)."""
    out = cold_python("from pnrotor.pn import evolve_many\n"
                      "from pnrotor.ode.dop853 import core, CORE_SIG\n"
                      "evolve_many([30.0, 12.0], [10.0, 8.0], [0.6, 0, 0.2], [0, 0, 0.1], 20.0)\n"
                      "print(list(core.overloads) == [tuple(CORE_SIG.args)], len(compiled),\n"
                      "      [n for n in compiled if 'raise_with_shape' in n])\n", timeout=900)
    one_core, n_compiled, error_paths = out.strip().split(" ", 2)
    assert one_core == "True" and int(n_compiled) > 10 and error_paths == "[]", out


def _assert_entry_same_as_single(pop, i, k, table, f_ref, f, options):
    _assert_same_state(pop, (i, k), _single_end(i, *table, f_ref, f, options), f)


@pytest.mark.parametrize("options", [{}, {"approximant": "T1", "rotor": "orbital", "atol": 1e-10}])
def test_a_list_of_frequencies_equals_single_evolves_to_each(options):
    """Unordered targets on both sides of f_ref, one beyond the end of every inspiral: each entry is what evolve
    with f_max (or f_min) there returns, bitwise, from one integration per direction."""
    table = _table(8, 5)
    M_sec = (table[0] + table[1]) * 4.925490947641267e-06
    beyond = 0.9 ** 3 / (np.pi * M_sec)            # v = 0.9: past the end of most inspirals here
    freqs = np.stack(np.broadcast_arrays(35.0, 12.0, beyond, 25.0, 16.0, 60.0), axis=1)
    pop = evolve_many(*table[:4], 20.0, frequencies=freqs, ell_hat=table[4], n_hat=table[5], **options)
    assert pop.v.shape == (8, 6) and pop.chi1.shape == (8, 6, 3) and pop.termination.shape == (8, 6)
    for i in range(8):
        for k, f in enumerate(freqs[i]):
            _assert_entry_same_as_single(pop, i, k, table, 20.0, f, options)
    assert np.all(pop.termination[:, [0, 3, 5]] == "f_max") and np.all(pop.termination[:, [1, 4]] == "f_min")
    assert "energy_balance" in set(pop.termination[:, 2]) and "invalid" not in set(pop.termination[:, 2])
    # one integration per direction: the forward targets share their step count, as do the backward ones
    assert np.all(pop.nfev[:, [0, 2, 3, 5]] == pop.nfev[:, [0]]) and np.all(pop.nfev[:, 1] == pop.nfev[:, 4])


def test_targets_on_the_last_step_of_a_run_that_ends_first():
    """Targets within the last step of an inspiral that ends by another event: just before that event the target
    is reached, just after it the run's end comes first, as the core decides between two events of one step."""
    table = tuple(x[[0, 2, 3]] for x in _table(4, 6))      # (the aligned binary 1 reaches v = 1)
    end = evolve_many(*table[:4], 20.0, ell_hat=table[4], n_hat=table[5])
    M_sec = (table[0] + table[1]) * 4.925490947641267e-06
    assert np.all(end.v < 0.9)
    freqs = np.stack([end.v ** 3 * (1 - 1e-7), end.v ** 3 * (1 + 1e-7), np.full(3, 0.9 ** 3)], axis=1) / (np.pi * M_sec)[:, None]
    pop = evolve_many(*table[:4], 20.0, frequencies=freqs, ell_hat=table[4], n_hat=table[5])
    assert np.all(pop.termination[:, 0] == "f_max") and np.all(pop.termination[:, 1:] == end.termination[:, None])
    for i in range(3):
        for k in range(3):
            _assert_entry_same_as_single(pop, i, k, table, 20.0, freqs[i, k], {})


def test_refused_targets_leave_the_others():
    pop = evolve_many([30.0, -1.0], [10.0, 10.0], [0, 0, 0.5], [0, 0, 0], 20.0,
                      frequencies=[30.0, 20.0, 1e-9, 15.0, 1e5])
    assert list(pop.termination[0]) == ["f_max", "invalid", "invalid", "f_min", "invalid"]
    assert "frequencies[1] = 20.0 Hz must be above f_ref" in pop.message[0, 1]
    assert "frequencies[2]" in pop.message[0, 2] and "at least" in pop.message[0, 2]
    assert "frequencies[4]" in pop.message[0, 4] and "at most" in pop.message[0, 4]
    assert np.all(np.isnan(pop.v[0, [1, 2, 4]])) and not np.any(np.isnan(pop.v[0, [0, 3]]))
    assert list(pop.termination[1]) == ["invalid"] * 5 and all("m1" in m for m in pop.message[1])


def test_targets_and_binaries_evolve_refuses_are_refused_alone():
    """A target that is not a finite positive frequency, in a per-binary table, and a negative f_ref, are
    'invalid' entries with evolve's messages; the other binaries and targets go on."""
    table = [[30.0, 15.0], [np.nan, 30.0], [-5.0, 0.0], [30.0, 15.0]]
    pop = evolve_many([30.0] * 4, [10.0] * 4, [0, 0, 0.5], [0, 0, 0], [20.0, 20.0, 20.0, -20.0], frequencies=table)
    assert [list(x) for x in pop.termination] == [["f_max", "f_min"], ["invalid", "f_max"], ["invalid"] * 2,
                                                  ["invalid"] * 2]
    for i, k in ((1, 0), (2, 0), (2, 1)):
        with pytest.raises(ValueError) as refusal:
            evolve(30.0, 10.0, [0, 0, 0.5], [0, 0, 0], 20.0, f_max=table[i][k])
        assert pop.message[i, k] == str(refusal.value).replace("f_max", f"frequencies[{k}]")
    with pytest.raises(ValueError) as refusal:
        evolve(30.0, 10.0, [0, 0, 0.5], [0, 0, 0], -20.0, f_max=30.0)
    assert list(pop.message[3]) == [str(refusal.value)] * 2
    np.testing.assert_array_equal(pop.v[1, 1], pop.v[0, 0])


@pytest.mark.parametrize("kwargs, match", [
    ({"frequencies": [30.0], "f_end": 30.0}, "not both"),
    ({"frequencies": np.ones((3, 2)) * 30}, "got m1 2, m2 2, frequencies 3"),
    ({"frequencies": []}, "K >= 1"),
    ({"frequencies": [30.0, "abc"]}, "frequencies must be numbers"), ({"frequencies": [True]}, "frequencies must be"),
    ({"frequencies": [[30.0], [30.0, 40.0]]}, "frequencies must be numbers"),
])
def test_bad_frequency_lists_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        evolve_many([30.0, 20.0], [10.0, 10.0], [0, 0, 0], [0, 0, 0], 20.0, **kwargs)


def test_per_binary_kappas_and_chunks_equal_single_evolve(monkeypatch):
    """Spin-induced quadrupoles differing per binary (the spin-independent parameters are built for a chunk of
    binaries at once, elementwise), and a table split into chunks of 5: still each binary's own evolve."""
    import pnrotor.pn.many as many
    monkeypatch.setattr(many, "CHUNK", 5)
    table = _table(12, 7)
    kappa1, kappa2 = np.linspace(1.0, 12.0, 12), np.linspace(20.0, 2.0, 12)
    pop = evolve_many(*table[:4], 20.0, ell_hat=table[4], n_hat=table[5], kappa1=kappa1, kappa2=kappa2)
    m1, m2, c1, c2, ell, nh = table
    for i in range(12):
        e = evolve(m1[i], m2[i], c1[i], c2[i], 20.0, ell_hat=ell[i], n_hat=nh[i], kappa1=kappa1[i], kappa2=kappa2[i],
                   sampling="final")
        assert pop.t[i] == e.t[-1] and pop.termination[i] == e.termination
        for k in FIELDS:
            np.testing.assert_array_equal(getattr(pop, k)[i], getattr(e, k)[-1], err_msg=f"binary {i}, {k}")


def test_a_target_an_ulp_from_f_ref_is_refused_as_evolve_refuses_it():
    """v = (πMf)^(1/3) maps a frequency an ulp from f_ref onto f_ref's own v, which evolve refuses as f_max or
    f_min (its checks are on v): such a target is 'invalid', and the binary's other targets go on (as the
    farthest target it must not make the whole binary invalid, as a nearer one not return another state)."""
    from pnrotor.pn.initial import total_mass_seconds, v_from_frequency
    M = total_mass_seconds(30.0, 10.0)
    # an f_ref whose neighbours an ulp up and an ulp down both give its v
    f_ref = next(f for f in np.arange(20.0, 21.0, 0.001) if all(
        v_from_frequency(np.nextafter(f, g), M) == v_from_frequency(f, M) for g in (0.0, 100.0)))
    up, down = float(np.nextafter(f_ref, 100.0)), float(np.nextafter(f_ref, 0.0))
    args = (30.0, 10.0, [0.3, 0.1, 0.4], [0.0, 0.2, -0.3], float(f_ref))
    for kw in ({"f_max": up}, {"f_min": down}):
        with pytest.raises(ValueError, match="f_max|f_min"):
            evolve(*args, **kw)
    pop = evolve_many([30.0], *args[1:], frequencies=[40.0, up, 10.0, down])
    assert list(pop.termination[0]) == ["f_max", "invalid", "f_min", "invalid"]
    assert "is too close to f_ref" in pop.message[0, 1] and "far enough below f_ref" in pop.message[0, 3]
    assert np.all(np.isnan(pop.v[0, [1, 3]]))
    alone = evolve_many([30.0], *args[1:], frequencies=[up, 10.0])
    assert list(alone.termination[0]) == ["invalid", "f_min"]
    np.testing.assert_array_equal(alone.chi1[0, 1], pop.chi1[0, 2])


def test_quantities_and_shared_masses_give_the_same_population():
    """Masses and frequencies as astropy Quantities (M_sun, grams; Hz, kHz) give the population of their values in
    M_sun and Hz, each binary bitwise what evolve gives for the same Quantities (they lost their units: 0.03 kHz
    was read as 0.03 Hz, a backward run); N comes from any per-binary input (scalar masses and f_ref with (N, 3)
    spins raised), 1 when every input is shared."""
    table = _table(4, 3)
    m1, m2, c1, c2 = table[:4]
    plain = evolve_many(m1, m2, c1, c2, 20.0, frequencies=[30.0, 15.0])
    with_units = evolve_many(m1 * u.M_sun, m2 * u.M_sun, c1, c2, 0.02 * u.kHz, frequencies=[30.0, 15.0] * u.Hz)
    for k in FIELDS + ("t", "t_seconds", "termination"):
        np.testing.assert_array_equal(getattr(with_units, k), getattr(plain, k), err_msg=k)
    assert plain.termination[0].tolist() == ["f_max", "f_min"]
    grams = evolve_many((m1 * u.M_sun).to(u.g), m2, c1, c2, 20.0, f_end=0.03 * u.kHz)
    single = evolve((m1[0] * u.M_sun).to(u.g), m2[0], c1[0], c2[0], 20.0, f_max=0.03 * u.kHz, sampling="final")
    assert grams.termination[0] == "f_max" and grams.t[0] == single.t[-1]
    for k in FIELDS:
        np.testing.assert_array_equal(getattr(grams, k)[0], getattr(single, k)[-1], err_msg=k)
    shared = evolve_many(30.0, 10.0, c1, c2, 20.0)
    one_by_one = evolve_many([30.0] * 4, [10.0] * 4, c1, c2, [20.0] * 4)
    length_one = evolve_many([30.0], [10.0], c1, c2, [20.0])   # as numpy broadcasts (a review: refused for a while)
    for k in FIELDS + ("t", "termination"):
        np.testing.assert_array_equal(getattr(length_one, k), getattr(one_by_one, k), err_msg=k)
    alone = evolve_many(30.0, 10.0, c1[2], c2[2], 20.0)
    assert len(shared) == 4 and len(alone) == 1
    for k in FIELDS + ("t", "termination"):
        np.testing.assert_array_equal(getattr(shared, k), getattr(one_by_one, k), err_msg=k)
        np.testing.assert_array_equal(getattr(alone, k)[0], getattr(one_by_one, k)[2], err_msg=k)


def test_an_invalid_binarys_refused_targets_get_the_message_evolve_gives_first():
    """A binary evolve refuses (|chi1| > 1, or f_ref past the end of its inspiral) with a list holding refused
    targets: each entry says what evolve with that target says first, in the order of its checks (the target's
    finiteness before the spins; the spins before the target's range; the target's range before the start check).
    Every entry carried the binary's message."""
    targets = [-1.0, 30.0, 1e4]
    pop = evolve_many([30.0, 30.0], [10.0, 10.0], [[0, 0, 1.5], [0, 0, 0.5]], [[0, 0, 0], [0, 0, -0.3]],
                      [20.0, 1000.0], frequencies=targets)
    assert pop.termination.tolist() == [["invalid"] * 3] * 2
    for i, (chi1, chi2, f_ref) in enumerate((([0, 0, 1.5], [0, 0, 0], 20.0), ([0, 0, 0.5], [0, 0, -0.3], 1000.0))):
        for k, f in enumerate(targets):
            side = "f_min" if f < f_ref else "f_max"
            with pytest.raises(ValueError) as refusal:
                evolve(30.0, 10.0, chi1, chi2, f_ref, **{side: f})
            assert pop.message[i, k] == str(refusal.value).replace(side, f"frequencies[{k}]"), (i, k)
    assert pop.message[0, 0].startswith("frequencies[0] must be a finite positive")
    assert pop.message[0, 2].startswith("|chi1| = 1.5") and pop.message[1, 1].startswith("f_ref = 1000.0 Hz is past")
    assert pop.message[1, 2].startswith("frequencies[2] = 10000.0 Hz gives v")


def _settings_table():
    """Binaries for population_settings: random valid ones (precessing, aligned, nonspinning, tilted frames) and
    rows that fail one check of binary_settings each or sit just inside its bound."""
    rng = np.random.default_rng(7)
    n = 24
    rows = []
    for i in range(n):
        c1, c2 = rng.uniform(-0.6, 0.6, 3), rng.uniform(-0.6, 0.6, 3)
        ell, nh = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
        if i % 3 == 1:
            ell, nh = np.array([0.6, 0.0, -0.8]), np.array([-0.8, 0.0, -0.6])
        if i % 4 == 0:
            c1, c2 = c1[2] * ell, c2[2] * ell
        if i % 4 == 1:
            c1, c2 = -0.0 * c1, 0.0 * c2          # nonspinning, signed zeros
        rows.append([rng.uniform(5, 40), rng.uniform(1, 20), c1, c2, 20.0, (np.nan, 12.0)[i % 2],
                     (np.nan, 100.0)[i % 3 == 0], ell, nh, 1.0, rng.uniform(0, 5)])
    z, x = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    base = [30.0, 10.0, np.array([0.1, 0.2, 0.3]), np.array([0.0, -0.4, 0.1]), 20.0, np.nan, np.nan, z, x, 1.0, 1.0]
    for k, value in [(0, -1.0), (0, np.nan), (1, np.inf), (0, 0.0), (0, 1e3), (0, 1e3 * (1.0 + 1e-9)),
                     (2, np.array([1.0, 0.0, 0.0])), (2, np.array([1.0, 1e-7, 0.0])), (3, np.array([0.0, np.nan, 0.0])),
                     (7, np.array([0.0, 0.0, 1.0 + 2e-8])), (7, np.array([0.0, 0.0, 1.0 + 5e-9])),
                     (8, np.array([1.0, 0.0, 2e-8])), (8, np.array([1.0, 0.0, 5e-9])), (8, np.array([0.0, 0.0, 1.0])),
                     (9, -1.0), (9, 0.0), (10, np.nan), (10, np.inf), (4, 1e-6), (4, 1e5), (4, -20.0), (4, np.inf),
                     (5, 20.0), (5, 25.0), (5, 1e-6), (5, 0.0), (5, -5.0), (5, np.inf), (5, 10.0),
                     (6, 20.0), (6, 15.0), (6, 1e5), (6, 5000.0), (6, np.inf), (6, 0.0), (6, 300.0),
                     (2, np.array([1.0 + 1e-13, 0.0, 0.0])), (7, np.array([-0.0, 0.0, 1.0])),
                     (2, np.array([1e-15, 0.0, 0.3])), (2, np.array([1e-13, 0.0, 0.3])),
                     # in-plane parts on the bound 1e-28 (a review: x ** 2 + y ** 2 by libm's pow and by products
                     # differ in the last bit here and classified these two differently)
                     (2, np.array([5.156205129505175e-15, 8.568170671879997e-15, 0.3])),
                     (2, np.array([6.382933472774764e-15, 7.697932208205753e-15, 0.3]))]:
        row = list(base)
        row[k] = value
        if k == 0 and value >= 1e3:
            row[1] = 1e-3              # m1/m2 = 1e6, the bound (allowed), and just beyond it
        if k == 7 and value[0] == 0.0:
            row[8] = np.array([1.0, 0.0, -0.0])   # signed zeros: R0 (1, -0, 0, 0), not the first row's (1, 0, 0, 0)
        if k == 2 and value[0] < 1e-12:
            row[3] = np.array([0.0, 0.0, -0.2])   # in-plane parts of 1e-15 (aligned) and 1e-13 (precessing)
        rows.append(row)
    rows.append([30.0, 10.0, 0.0 * z, 0.0 * z, 20.0, np.nan, np.nan, np.array([-0.6, 0.0, 0.8]),
                 np.array([0.8, 0.0, 0.6]), 1.0, 1.0])
    return [np.array([r[k] for r in rows], dtype=np.float64) for k in range(11)]


@pytest.mark.parametrize("integrate_rotor", [False, True])
def test_population_settings_are_binary_settings_row_by_row(integrate_rotor):
    """evolve_many checks and converts a whole population at once (settings.population_settings): a row it calls
    valid must hold bitwise binary_settings' numbers (signed zeros too), and binary_settings must refuse every row
    it does not call valid (each edge row fails one check, or sits just inside a bound)."""
    from pnrotor import Options
    from pnrotor.pn.settings import binary_settings, checked, population_settings
    o = checked(Options(integrate_rotor=integrate_rotor, max_steps=1000), "final")
    table = _settings_table()
    b = population_settings(o, *table)
    n_valid = 0
    for i in range(table[0].size):
        m1, m2, c1, c2, f_ref, f_min, f_max, ell, nh, k1, k2 = (x[i].tolist() for x in table)
        try:
            s = binary_settings(o, m1, m2, c1, c2, f_ref, None if math.isnan(f_min) else f_min,
                                None if math.isnan(f_max) else f_max, ell, nh, k1, k2)
        except ValueError:
            assert not b.valid[i], i
            continue
        assert b.valid[i], i
        n_valid += 1
        assert b.aligned[i] == s.use_aligned
        for name in ("M_sec", "X1", "nu", "v0", "v_max", "chi1", "chi2", "ell_hat", "R0"):
            assert np.asarray(getattr(b, name)[i]).tobytes() == np.asarray(getattr(s, name)).tobytes(), (i, name)
        assert (np.isnan(b.v_min[i]) and s.v_min is None) or b.v_min[i].tobytes() == np.float64(s.v_min).tobytes()
    assert 24 < n_valid < table[0].size - 20
    assert {False, True} <= set(b.aligned[b.valid]) or integrate_rotor


def test_an_exception_on_one_thread_stops_the_loop_within_a_block(monkeypatch):
    """The CLI's SIGTERM raises KeyboardInterrupt on the calling thread between two of its blocks of halves: the other
    thread takes no further block (a review: it integrated the rest of the group alone, as long as the whole call)."""
    import threading
    import time

    from pnrotor import threads
    from pnrotor.pn import many

    calls = []

    def loop(lo, hi, *args):
        calls.append(lo)
        if threading.current_thread() is threading.main_thread() and len(calls) >= 3:
            raise KeyboardInterrupt
        time.sleep(0.02)

    loop.overloads = {"compiled": None}
    monkeypatch.setattr(many, "_integrate_all", loop)
    monkeypatch.setattr(threads, "thread_count", lambda: 2)
    table = _table(200, 6)
    with pytest.raises(KeyboardInterrupt):
        evolve_many(*table[:4], 20.0, ell_hat=table[4], n_hat=table[5])
    assert 3 <= len(calls) <= 5 and threads._busy == 0   # of ~13 blocks in the first group
