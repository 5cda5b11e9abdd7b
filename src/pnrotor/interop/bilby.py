"""bilby: pnrotor's waveform as a bilby waveform generator, by name from a bilby_pipe ini file.

:class:`PNRotorWaveformGenerator` is bilby's ``GWSignalWaveformGenerator`` with pnrotor's gwsignal generator
(:class:`pnrotor.interop.gwsignal.PNRotorGenerator`): bilby's standard parameters (mass_1, mass_2, a_1, tilt_1,
phi_12, a_2, tilt_2, phi_jl, theta_jn, phase, luminosity_distance) become LAL's spins at the reference frequency
(``bilby_to_lalsimulation_spins``), gwsignal conditions the time-domain waveform (taper, high-pass) and Fourier
transforms it, and bilby places it at geocent_time.  In a bilby_pipe ini file::

    waveform-generator = pnrotor.interop.bilby.PNRotorWaveformGenerator
    waveform-approximant = PNRotorT4
    reference-frequency = 20
    pn-amplitude-order = 0
    waveform-arguments-dict = {ell_max: 4, atol: 1e-10}

(bilby_pipe names a waveform-generator class by its path, while its source model is only ever a frequency-domain
one; a time-domain source function could not be named there).  ``pn_amplitude_order``, ``pn_phase_order``,
``pn_spin_order`` and ``pn_tidal_order`` are LAL's integers (:mod:`pnrotor.interop.pipelines`; bilby's default
amplitude order 0); entries of the waveform-arguments dict other than bilby's own are pnrotor's options.  bilby's
binary-neutron-star parameters lambda_1, lambda_2 (e.g. from ``convert_to_lal_binary_neutron_star_parameters``)
are the tidal deformabilities Λ₁, Λ₂.  In Python::

    generator = PNRotorWaveformGenerator(duration=8, sampling_frequency=2048,
                                         waveform_arguments=dict(waveform_approximant="PNRotorT4",
                                                                 reference_frequency=20, minimum_frequency=20))
"""

from bilby.gw.waveform_generator import GWSignalWaveformGenerator

from pnrotor.interop.gwsignal import PNRotorGenerator

__all__ = ["PNRotorWaveformGenerator"]

ORDERS = {"pn_amplitude_order": "amplitude_order", "pn_phase_order": "phase_order", "pn_spin_order": "spin_order",
          "pn_tidal_order": "tidal_order"}
"""bilby's waveform arguments of the PN orders → PNRotorGenerator's options."""


class PNRotorWaveformGenerator(GWSignalWaveformGenerator):
    """bilby's ``GWSignalWaveformGenerator`` making pnrotor's waveform (module docstring); waveform_approximant
    'PNRotorT1', 'PNRotorT4' or 'PNRotorT5'."""

    generator_pickles = True   # PNRotorGenerator is plain data: it pickles with the waveform generator

    def _create_generator(self, waveform_approximant=None):
        arguments = self.waveform_arguments
        options = {name: arguments.get(key, 0 if key == "pn_amplitude_order" else -1) for key, name in ORDERS.items()}
        return PNRotorGenerator(waveform_approximant or self.waveform_approximant, **options)
