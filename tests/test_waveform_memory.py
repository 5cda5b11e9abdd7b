"""The nonlinear memory of the m = 0 modes (pnrotor.waveform.memory, Favata 2009's closed form through 3PN) against
the memory's rate evaluated numerically from pnrotor's own oscillatory modes along a run.

ḣ^mem_ℓ0 = −√((ℓ−2)!/(ℓ+2)!) ∮ dΩ |ḣ|² Y*_ℓ0, ḣ = Σ ḣ_ℓ'm' ₋₂Y_ℓ'm' (units r h/M, t in M; LALSuite's mode signs),
with ḣ_ℓm = −imΦ̇ h_ℓm (the amplitudes' own rate enters at 5PN) and the angular integral ∮ ₋₂Y_ℓ'm' ₋₂Y*_ℓ''m' Y*_ℓ0
by Gauss–Legendre quadrature, against the time derivative of the closed form along the run (the memory itself is
the integral of this rate since t → −∞): both are PN expansions through 3PN of the same quantity, so their relative
difference must vanish as v⁷ (measured on the run below: (2,0) 1.3e-5 at v = 0.13, 3.9e-5 at 0.15, 1.6e-4 at 0.18,
a log-log slope of 7.3; (4,0) 6.0e-5, 1.7e-4, 6.3e-4, slope 7.2).  Without the 3PN term of (2,0) the difference
is 2.1e-5 at v = 0.13 and its slope 4.6.  Late in the run, at v = 0.25, the memory accumulated since its start, the
rate integrated, is the closed form's h_ℓ0(v) − h_ℓ0(v₀) within 6e-4 ((2,0)) and 2e-3 ((4,0)).
"""

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

from pnrotor.pn import evolve
from pnrotor.waveform.amplitudes import coorbital_modes
from pnrotor.waveform.layout import ell_m, mode_index
from pnrotor.waveform.modes import modes
from pnrotor.waveform.polarizations import swsh

M1, M2 = 10.0, 5.0


@pytest.fixture(scope="module")
def run():
    return evolve(M1, M2, (0, 0, 0), (0, 0, 0), 8.0, f_max=400.0, sampling=("per_orbit", 16))


def _memory_rate(run, ell, H):
    """ḣ^mem_ℓ0 from the co-orbital modes H (module docstring)."""
    x, w = np.polynomial.legendre.leggauss(80)
    theta = np.arccos(x)
    Y = swsh(0, ell, 0, theta, 0.0).real
    v = run.v
    rate = np.zeros_like(v)
    for l1, m in ell_m(8):
        for l2 in range(max(2, abs(m)), 9):
            G = 2 * np.pi * np.sum(w * swsh(-2, l1, m, theta, 0.0) * np.conj(swsh(-2, l2, m, theta, 0.0)) * Y)
            rate += (m * m * v ** 6 * H[mode_index(l1, m)] * np.conj(H[mode_index(l2, m)]) * G).real
    return -math.sqrt(math.factorial(ell - 2) / math.factorial(ell + 2)) * rate


@pytest.mark.parametrize("ell, bounds", [(2, (3e-5, 1e-4, 4e-4)), (4, (1.5e-4, 4e-4, 1.5e-3))])
def test_closed_form_is_the_memory_integral(run, ell, bounds):
    H = coorbital_modes(run.v, None, None, M1, M2, 8, 6)
    memory = coorbital_modes(run.v, None, None, M1, M2, 8, 6, memory=True)[mode_index(ell, 0)] - H[mode_index(ell, 0)]
    assert np.all(memory.imag == 0) and np.all(np.diff(memory.real) < 0)   # growing, in LALSuite's sign
    closed = np.gradient(memory.real, run.t, edge_order=2)
    rate = _memory_rate(run, ell, H)
    points = (0.13, 0.15, 0.18)
    errors = [abs(rate[i] / closed[i] - 1) for i in np.searchsorted(run.v, points)]
    assert all(e < b for e, b in zip(errors, bounds)), errors
    assert math.log(errors[2] / errors[0]) / math.log(points[2] / points[0]) > 6.5, errors   # v⁷: beyond 3PN
    # late in the run (v = 0.25, from v₀ = 0.123): the memory accumulated since its start
    late = np.searchsorted(run.v, 0.25)
    accumulated = cumulative_simpson(rate, x=run.t, initial=0.0)[late]
    assert accumulated == pytest.approx(memory.real[late] - memory.real[0], rel=bounds[2] * 5)


def test_memory_option_adds_only_the_m0_modes_and_starts_at_its_closed_form(run):
    plain, with_memory = modes(run, 4), modes(run, 4, memory=True)
    for row, (ell, m) in enumerate(plain.ell_m):
        if m or ell % 2:
            np.testing.assert_array_equal(with_memory.data[row], plain.data[row])
    h20 = with_memory.data[with_memory.ell_m.index((2, 0))]
    nu, v0 = M1 * M2 / (M1 + M2) ** 2, run.v[0]
    leading = -5 / (14 * math.sqrt(6)) * 8 * math.sqrt(math.pi / 5) * nu * v0 ** 2   # Favata 2009 Eq. (4.3a)
    assert h20[0].real == pytest.approx(leading, rel=0.02) and with_memory.inputs["memory"] is True
    assert "memory" not in plain.inputs
    newtonian = modes(run, 2, 0.0, memory=True).data[0:5]       # the memory at the amplitude order: v⁰ only
    np.testing.assert_allclose(newtonian[2].real, -5 / (14 * math.sqrt(6)) * 8 * math.sqrt(math.pi / 5) * nu * run.v ** 2,
                               rtol=1e-14)
    with pytest.raises(ValueError, match="memory must be True or False"):
        modes(run, 4, memory="yes")
