"""The `pnrotor` command line: a thin layer that parses, calls the library, prints and exits.

One module per subcommand (`verify`, `bench`, `evolve`, `inspect`, `plot`), each with
``add_parser(subparsers)`` that registers its arguments and sets ``func`` to a ``run(args) -> int``;
an option several subcommands take is added by one helper here (`add_damping_option`).
Errors in the user's input (argparse's, ``ValueError``, ``FileNotFoundError``, ``FileExistsError``,
``IsADirectoryError``, or a `UsageError` raised by a subcommand) are printed as one line on stderr with
exit status 2 and no traceback; other failures of the system (``OSError``: a full disk, a permission) as
one line with exit status 1; Ctrl-C, SIGTERM and SIGHUP stop a command with exit status 130 (a signal set to be
ignored when the command starts, as ``nohup`` does SIGHUP, stays ignored: `pnrotor.signals`).
"""

import argparse
import importlib
import math
import re
import signal
import sys

from pnrotor import signals

SUBCOMMANDS = ("verify", "bench", "evolve", "inspect", "plot")


class UsageError(Exception):
    """A problem with the command line or its input that the user can fix."""


DAMPING = (0.01, 0.01)
"""The damping rates of `pnrotor.integrate_angular_velocity`, the default of ``--damping``."""


def add_damping_option(parser):
    """``--damping LAMBDA MU``: the damping rates of vectors-damped (`verify` and `bench`); None when not given
    (`DAMPING` then)."""
    parser.add_argument("--damping", type=_rate, nargs=2, metavar=("LAMBDA", "MU"),
                        help=f"damping rates of vectors-damped, finite and >= 0 (default: {DAMPING[0]} {DAMPING[1]})")


def _rate(text):
    """A finite float ≥ 0 from the command line (argparse's type), or the parser's one-line error."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text!r}")
    return value


class _Parser(argparse.ArgumentParser):
    """argparse's parser, whose errors (an unknown option, a value of the wrong type) are one line on stderr
    and exit status 2, as every other error of the command line, not the usage block and then the error; and
    which takes an argument starting as a negative number (``--t-end -1e6``, ``--chi1 -0.6,0,0.2``) or ``-inf``
    as a value, where argparse of Python 3.11–3.13.0 takes only ``-5`` and ``-0.5`` whole and reads the others
    as unknown options (later versions match such a prefix, ``-\\.?\\d``, too)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"-\.?\d|-inf", re.IGNORECASE)   # re.match: a prefix

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser():
    from pnrotor import __version__

    parser = _Parser(
        prog="pnrotor",
        description="Orientation of precessing compact binaries by integrating the rotor (Boyle 2016).",
    )
    parser.add_argument("--version", action="version", version=f"pnrotor {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in SUBCOMMANDS:
        importlib.import_module(f"pnrotor.cli.{name}").add_parser(subparsers)
    return parser


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    # SIGTERM and SIGHUP stop a command like Ctrl-C
    previous = signals.take(_interrupt, [s for s in signals.STOPPING if s != signal.SIGINT])
    try:
        return int(args.func(args) or 0)
    except (UsageError, ValueError, FileNotFoundError, FileExistsError, IsADirectoryError) as error:
        print(f"pnrotor {args.command}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as interrupt:
        print(f"pnrotor {args.command}: interrupted" + (f"; {interrupt}" if str(interrupt) else ""), file=sys.stderr)
        return 130
    except OSError as error:  # a full disk, a lost permission...: what the system said, in one line
        print(f"pnrotor {args.command}: error: {error}", file=sys.stderr)
        return 1
    except MemoryError as error:  # what the memory checks before allocating could not foresee (another process's use)
        print(f"pnrotor {args.command}: error: out of memory" + (f": {error}" if str(error) else ""), file=sys.stderr)
        return 1
    finally:
        signals.restore(previous)


if __name__ == "__main__":
    sys.exit(main())
