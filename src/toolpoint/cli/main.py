"""``toolpoint`` console script.

Each sub-command lives in its own module ``toolpoint.cli.<name>`` exposing
``register(subparsers)``, which adds its parser and sets ``func(args) -> int``.
Bad input (:class:`toolpoint.errors.InputError`) becomes one line on stderr and
exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import InputError

# Order is the order shown in --help.
COMMANDS = ("frf", "identify", "reproduce", "campaign", "predict", "anfis", "lobes")


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__

    p = argparse.ArgumentParser(
        prog="toolpoint",
        description="Tool-point FRF prediction: receptance coupling, joint identification, ANFIS, stability lobes.",
    )
    p.add_argument("--version", action="version", version=f"toolpoint {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"{__package__}.{name}").register(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        code = args.func(args)
    except InputError as err:
        print(f"toolpoint {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"toolpoint {args.command}: interrupted", file=sys.stderr)
        return 130
    return int(code or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
