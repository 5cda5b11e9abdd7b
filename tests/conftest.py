"""Hypothesis profiles: ``default`` draws the same examples on every run (derandomized), so the suite
and CI pass or fail reproducibly; ``explore`` draws new random examples each run, to hunt for new
failures: ``python3 -m pytest --hypothesis-profile=explore``.  (A random run found the degenerate binary
of tests/test_integrate.py::test_generator_on_the_half_pi_sphere_converges.)"""

from hypothesis import settings

settings.register_profile("default", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("default")
