"""``toolpoint`` console script.

Each sub-command lives in its own module ``toolpoint.cli.<name>`` exposing
``register(subparsers)``, which adds its parser and sets ``func(args) -> int``.
Only the module of the command being run is imported (the others get a stub
parser that carries their one-line help), so ``toolpoint --version`` and
``toolpoint --help`` start without NumPy, SciPy or matplotlib.

Bad input (:class:`toolpoint.errors.InputError`) becomes one line on stderr and
exit code 2, never a traceback; so does a bad command-line value.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import re
import sys

from .. import __version__
from ..errors import InputError

# name → one-line help, in the order shown by --help
COMMANDS = {
    "frf": "tool-point (or holder-tip) receptance of an assembly by RCSA",
    "identify": "identify the holder–tool joint from a measured tool-point FRF",
    "reproduce": "the paper's numerical case: Table 1 and Fig. 4 with GA, SA, PSO and hybrid",
    "campaign": "many tools on one spindle–holder: synthesise, identify all, learn ANFIS",
    "predict": "tool-point FRF of an unmeasured tool from the ANFIS-predicted joint",
    "anfis": "ANFIS (MATLAB genfis + anfis hybrid learning): train a model on a CSV table, or predict with one",
    "modal": "common-pole modal fit of one or several FRFs → natural frequencies, damping, modal constants",
    "check": "check measured FRFs before trusting them: band, modes with a confidence word, coherence, problems",
    "lobes": "stability lobe diagram from a tool-point FRF (zero-order or semi-discretisation)",
    "tap": "impact-test records (time, force, response) → FRF with coherence",
    "library": "safe spindle speeds and depths for every tool of a tool library, with their uncertainty",
    "report": "one self-contained HTML page of a library run (sortable overview, per-tool figures)",
    "cut": "chatter detection from a record of a cut (audio, accelerometer, UFF58): verdict, chatter frequency",
    "update": "test cuts → posterior lobes (5/50/95 %%), P(stable) map, parameters, the next test cut",
    "simulate": "time-domain simulation of one milling cut: forces, chatter, surface location error, surface",
    "map": "simulated stability and surface location error over a speed × depth grid, beside the SDM lobes",
}


_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-inf$")


class _Parser(argparse.ArgumentParser):
    """argparse with one error format: a single line ``toolpoint CMD: error: …`` and exit 2 (no usage block).

    Negative numbers in any notation (``-6e8``, ``-.5``) are taken as values, to be judged by the
    command, not read as unknown options (argparse's own rule knows only ``-6`` and ``-0.5``).
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER
        self._seen: list[str] = []
        self.removed: dict[str, str] = {}  # option of an earlier version → what to give instead

    _innermost: "_Parser | None" = None  # the (sub-)command parser that ran last: the one that owns the words

    def parse_known_args(self, args=None, namespace=None):
        self._seen = list(sys.argv[1:] if args is None else args)
        _Parser._innermost = self
        return super().parse_known_args(args, namespace)

    def _unknown_option(self) -> str | None:
        """The first ``--word`` on the command line that is no option of this parser, with the closest valid one.

        A typo is the likely cause of most other errors ("the following arguments are required: --out" after
        ``--outt``), so it is named first.
        """
        known = [s for s in self._option_string_actions if s.startswith("--")]
        removed = getattr(self, "removed", {})
        for word in self._seen:
            if word == "--":
                break
            name = word.split("=", 1)[0]
            if name in removed:
                return f"{name} is no longer an option: give {removed[name]}"
            if not name.startswith("--") or name in known or any(k.startswith(name) for k in known):
                continue
            close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
            return f"unknown option {name}" + (f" (did you mean {close[0]}?)" if close else "")
        return None

    def error(self, message):
        message = " ".join(str(message).split())
        # unrecognised words reach the top-level parser: judge them against the sub-command that got them
        owner = _Parser._innermost if message.startswith("unrecognized arguments") and _Parser._innermost else self
        typo = owner._unknown_option()
        if typo:
            message = typo
        self.exit(2, f"{owner.prog}: error: {message} (see --help)\n")


def _command_in(argv: list[str]) -> str | None:
    """The sub-command named on the command line (the first word that is one)."""
    for word in argv:
        if word in COMMANDS:
            return word
        if not word.startswith("-"):
            return None
    return None


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The ``toolpoint`` parser; only the command named in ``argv`` is built in full.

    With ``argv=None`` every command is built (for documentation tools).
    """
    p = _Parser(
        prog="toolpoint",
        description="Tool-point FRF prediction: receptance coupling, joint identification, ANFIS, stability lobes.",
    )
    p.add_argument("--version", action="version", version=f"toolpoint {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)
    wanted = COMMANDS if argv is None else {_command_in(argv)}
    for name, help_text in COMMANDS.items():
        if name in wanted:
            importlib.import_module(f"{__package__}.{name}").register(sub)
        else:
            sub.add_parser(name, help=help_text)
    _describe(p)
    return p


def _describe(parser: argparse.ArgumentParser) -> None:
    """Give every (sub-)command without a description its one-line help as description (shown by ``--help``)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help for a in action._choices_actions}
            for name, sp in action.choices.items():
                if not sp.description and helps.get(name):
                    sp.description = helps[name][0].upper() + helps[name][1:] + "."
                _describe(sp)


def _terminate_cleanly() -> None:
    """SIGTERM (a kill, a scheduler's time-out) unwinds like Ctrl-C: atomic writes remove their temporary files
    and finished work stays; the exit code is 143 (128 + 15). Only in the main thread (signal's rule)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return

    def stop(signum, frame):
        raise SystemExit(143)

    try:
        signal.signal(signal.SIGTERM, stop)
    except (ValueError, OSError):  # not settable here (embedded interpreter): the default action stays
        pass


def main(argv: list[str] | None = None) -> int:
    """Run ``toolpoint`` with ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    argv = sys.argv[1:] if argv is None else list(argv)
    _terminate_cleanly()
    # NumPy's large temporaries reused, not mapped afresh page by page: a fifth of an update's CPU on a VM
    from ..memory import keep_freed_memory

    keep_freed_memory()
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    try:
        code = args.func(args)
    except InputError as err:
        print(f"toolpoint {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"toolpoint {args.command}: interrupted", file=sys.stderr)
        return 130
    except MemoryError as err:  # a record or a job too large for this machine: one line, what to make smaller
        what = " ".join(str(err).split()) or "no detail"
        print(f"toolpoint {args.command}: error: not enough memory ({what}); give a shorter record or a smaller job "
              "(fewer samples, speeds or points)", file=sys.stderr)
        return 2
    except OSError as err:  # the operating system's refusals (full disk, permission, name too long): one line
        name = InputError("", file=err.filename).file if err.filename else "file system"
        print(f"toolpoint {args.command}: error: {name}: {err.strerror or err}", file=sys.stderr)
        return 2
    return int(code or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
