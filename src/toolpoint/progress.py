"""Progress of long work on stderr: a tqdm bar on a terminal, a plain line every few seconds in a log.

tqdm alone disables itself (``disable=None``) or writes carriage-return redraws when stderr is not a
terminal; a run under ``nohup``, a scheduler or CI then shows nothing useful for minutes. This keeps one
behaviour for every long command.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]


class Progress:
    """Count finished work and report it on stderr.

    Parameters
    ----------
    total : int
        Units of work.
    desc : str
        What is counted (printed first).
    unit : str, default "item"
        Name of one unit.
    enabled : bool, default True
        False reports nothing.
    every_s : float, default 5.0
        Seconds between lines when stderr is not a terminal.
    stream : file-like, optional
        Where to write (default ``sys.stderr``); a terminal gets a tqdm bar.

    Examples
    --------
    >>> import io
    >>> log = io.StringIO()
    >>> with Progress(3, "campaign", "tool", every_s=0.0, stream=log) as p:
    ...     p.update(2)
    ...     p.update(1)
    >>> log.getvalue().splitlines()[-1].startswith("campaign: 3/3 tools (100 %)")
    True
    """

    def __init__(self, total: int, desc: str, unit: str = "item", *, enabled: bool = True, every_s: float = 5.0,
                 stream=None):
        self.total, self.desc, self.unit = int(total), desc, unit
        self.n = 0
        self.every_s = float(every_s)
        self.stream = sys.stderr if stream is None else stream
        self.t0 = self._last = time.monotonic()
        self._bar = None
        self.enabled = bool(enabled)
        if self.enabled and getattr(self.stream, "isatty", lambda: False)():
            from tqdm import tqdm

            self._bar = tqdm(total=self.total, desc=desc, unit=unit, file=self.stream)

    def update(self, n: int = 1) -> None:
        """Record ``n`` more finished units."""
        self.n += n
        if self._bar is not None:
            self._bar.update(n)
        elif self.enabled and time.monotonic() - self._last >= self.every_s:
            self._line()

    def _line(self) -> None:
        self._last = time.monotonic()
        pct = 100.0 * self.n / self.total if self.total else 100.0
        print(f"{self.desc}: {self.n}/{self.total} {self.unit}s ({pct:.0f} %), {self._last - self.t0:.0f} s",
              file=self.stream, flush=True)

    def close(self) -> None:
        """End the report (a final line in a log, if anything was done since the last one)."""
        if self._bar is not None:
            self._bar.close()
        elif self.enabled and self.total and (self.n != getattr(self, "_said", -1)):
            self._said = self.n
            self._line()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
