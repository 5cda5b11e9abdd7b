"""The `pnrotor` command line: a thin layer that parses, calls the library, prints and exits.

One module per subcommand (`verify`, `bench`, `evolve`, `inspect`, `plot`), each with
``add_parser(subparsers)`` that registers its arguments and sets ``func`` to a ``run(args) -> int``;
an option several subcommands take is added by one helper here (`add_damping_option`).
Errors in the user's input (argparse's, ``ValueError``, ``FileNotFoundError``, ``FileExistsError``,
``IsADirectoryError``, or a `UsageError` raised by a subcommand) are printed as one line on stderr with
exit status 2 and no traceback; other failures of the system (``OSError``: a full disk, a permission) as
one line with exit status 1; Ctrl-C, SIGTERM and SIGHUP stop a command with exit status 130.
"""

import argparse
import importlib
import math
import signal
import sys
import threading

SUBCOMMANDS = ("verify", "bench", "evolve", "inspect", "plot")


class UsageError(Exception):
    """A problem with the command line or its input that the user can fix."""


def add_damping_option(parser):
    """``--damping LAMBDA MU``: the damping rates of vectors-damped (`verify` and `bench`), by default
    those of `pnrotor.integrate_angular_velocity`."""
    parser.add_argument("--damping", type=_finite, nargs=2, default=(0.01, 0.01), metavar=("LAMBDA", "MU"),
                        help="damping rates of vectors-damped (default: 0.01 0.01)")


def _finite(text):
    """A finite float from the command line (argparse's type), or the parser's one-line error."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value


class _Parser(argparse.ArgumentParser):
    """argparse's parser, whose errors (an unknown option, a value of the wrong type) are one line on stderr
    and exit status 2, as every other error of the command line, not the usage block and then the error."""

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
    previous = {}
    if threading.current_thread() is threading.main_thread():  # SIGTERM and SIGHUP stop a command like Ctrl-C
        for name in ("SIGTERM", "SIGHUP"):
            if hasattr(signal, name):
                previous[getattr(signal, name)] = signal.signal(getattr(signal, name), _interrupt)
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
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)


if __name__ == "__main__":
    sys.exit(main())
