"""pnrotor: orientation of precessing compact binaries by integrating the rotor (Boyle 2016)."""

__version__ = "0.1.0"
