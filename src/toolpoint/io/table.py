"""CSV tables read one way: every unreadable file becomes one :class:`~toolpoint.errors.InputError`.

The project's tables (campaign ``measurements.csv`` and ``identified.csv``, ANFIS
training data, the tool library, the library's ``recommendations.csv``) are
small CSV files written by people and spreadsheets. Reading them can fail in the
operating system (missing file, a folder, no permission), in decoding (not
UTF-8, binary) or in the CSV parser (a NUL byte, a runaway quote); all of these
must reach the user as one line naming the file, never as a traceback.
"""

from __future__ import annotations

import csv
import os
import re
import stat
from pathlib import Path

from ..errors import InputError

_DECIMAL_COMMA = re.compile(r"\s*[+-]?\d*,\d+(?:[eE][+-]?\d+)?\s*")  # "-0,5", ",5", "1,25e-3"

__all__ = ["read_rows", "read_table", "text_encoding", "csv_safe", "csv_unsafe", "check_regular_file"]


def text_encoding(head: bytes) -> str:
    """The codec of a text file from its first two bytes: ``utf-16`` after a UTF-16 byte-order mark (a spreadsheet's
    "Unicode text" export), else ``utf-8-sig`` (UTF-8 with or without its mark). The one rule of the text readers.

    Examples
    --------
    >>> text_encoding("a,b".encode("utf-16")), text_encoding(b"a,")
    ('utf-16', 'utf-8-sig')
    """
    return "utf-16" if head[:2] in (b"\xff\xfe", b"\xfe\xff") else "utf-8-sig"


def read_rows(path: str | os.PathLike, *, what: str = "CSV") -> list[tuple[int, list[str]]]:
    """The non-blank rows of a CSV file with their line numbers (1-based, as an editor shows them).

    UTF-8 with or without a byte-order mark, or UTF-16 with it; a row whose cells are all blank is skipped. Cells are
    split at commas, or at semicolons or tabs where the first line holds more of them than commas (a spreadsheet's
    export; there, in a locale whose decimal mark is the comma, ``0,5`` is read as ``0.5``).

    Parameters
    ----------
    path : str or path-like
        The file.
    what : str, default "CSV"
        What the file is, for the message (e.g. ``"the tool library"``).

    Raises
    ------
    InputError
        A missing file, a folder, an unreadable or undecodable file, or CSV syntax
        the parser refuses (field ``file``'s name in the message).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "t.csv"
    >>> _ = p.write_text("a,b\\n\\n1,2\\n")
    >>> read_rows(p)
    [(1, ['a', 'b']), (3, ['1', '2'])]
    >>> _ = p.write_text("rpm;depth_mm;result\\n20000;0,5;stable\\n")
    >>> read_rows(p)
    [(1, ['rpm', 'depth_mm', 'result']), (2, ['20000', '0.5', 'stable'])]
    """
    p = Path(path)
    if p.is_dir():
        raise InputError(f"cannot read {what}: is a folder, not a file", file=p)
    if p.exists():
        check_regular_file(p, what=what)
    try:
        with open(p, "rb") as fb:
            enc = text_encoding(fb.read(2))
        with open(p, newline="", encoding=enc) as fh:
            first = ""
            for first in fh:  # the first non-blank line decides the delimiter
                if first.strip():
                    break
            fh.seek(0)
            if fh.read(1) != "\ufeff":  # the codec already skipped a BOM; seek(0) brought it back
                fh.seek(0)
            delim = max((",", ";", "\t"), key=first.count) if first.count(",") < max(first.count(";"),
                                                                                     first.count("\t")) else ","
            reader = csv.reader(fh, delimiter=delim)
            rows = [(reader.line_num, row) for row in reader if any(c.strip() for c in row)]
            if delim != ",":  # a spreadsheet that writes ';' or a tab between cells may write ',' as the decimal mark
                rows = [(n, [c.replace(",", ".") if _DECIMAL_COMMA.fullmatch(c) else c for c in r])
                        for n, r in rows]
            return rows
    except FileNotFoundError:
        raise InputError(f"cannot read {what}: file not found", file=p) from None
    except UnicodeDecodeError as err:
        raise InputError(f"cannot read {what}: not {'UTF-16' if enc == 'utf-16' else 'UTF-8'} text (byte {err.start})",
                         file=p) from None
    except (OSError, csv.Error) as err:
        raise InputError(f"cannot read {what}: {getattr(err, 'strerror', None) or err}", file=p) from None


def read_table(path: str | os.PathLike, *, what: str = "CSV") -> tuple[list[str], list[tuple[int, dict]]]:
    """Header (stripped names) and (line number, row dict) of every data row of a CSV file.

    Like :class:`csv.DictReader`: a short row has ``None`` for its missing cells, a
    long row keeps its extra cells under the key ``None``. An empty file has an
    empty header and no rows.

    Raises
    ------
    InputError
        As :func:`read_rows`.
    """
    rows = read_rows(path, what=what)
    if not rows:
        return [], []
    header = [h.strip() for h in rows[0][1]]
    out = []
    for line, row in rows[1:]:
        d: dict = dict(zip(header, row))
        if len(row) < len(header):
            d.update({h: None for h in header[len(row):]})
        elif len(row) > len(header):
            d[None] = row[len(header):]
        out.append((line, d))
    return header, out


_FORMULA = ("=", "+", "-", "@", "\t", "\r")


def csv_safe(value) -> str:
    """A CSV cell a spreadsheet will not run as a formula (OWASP's "CSV injection" rule).

    Text starting with ``= + - @``, a tab or a carriage return (after any ``'``) gets the standard quote prefix
    ``'``; numbers (``-1.5``, ``+3e-7``) stay numbers. :func:`csv_unsafe` undoes it when toolpoint reads its own
    files back.

    Examples
    --------
    >>> csv_safe("=cmd|' /C calc'!A0"), csv_safe("-1.5"), csv_safe("EM10-45"), csv_safe(2.5)
    ("'=cmd|' /C calc'!A0", '-1.5', 'EM10-45', '2.5')
    """
    text = str(value)
    if text.lstrip("'").startswith(_FORMULA):  # "'=x" too, or csv_unsafe would read it back as "=x"
        try:
            float(text)
            return text
        except ValueError:
            return "'" + text
    return text


def csv_unsafe(text: str) -> str:
    """The cell as written before :func:`csv_safe` (the ``'`` it put before a formula character removed).

    Examples
    --------
    >>> [csv_unsafe(csv_safe(s)) for s in ("=1+1", "'=1+1", "''@x", "'a", "-1.5")]
    ['=1+1', "'=1+1", "''@x", "'a", '-1.5']
    """
    return text[1:] if text.startswith("'") and text.lstrip("'").startswith(_FORMULA) else text


def check_regular_file(path, *, what: str = "file") -> Path:
    """``path`` as a Path if it is a regular file; else one line naming it (missing, a folder, a FIFO, a device).

    Every reader calls this before opening: opening a FIFO (named pipe) for reading blocks until something writes
    to it, i.e. for ever, and a device can stream without end.

    Examples
    --------
    >>> import os, tempfile
    >>> d = tempfile.mkdtemp(); fifo = os.path.join(d, "p"); os.mkfifo(fifo)
    >>> check_regular_file(fifo, what="FRF file")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: ...p: cannot read FRF file: not a regular file (a FIFO/named pipe)
    """
    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise InputError(f"cannot read {what}: file not found", file=p) from None
    except OSError as exc:
        raise InputError(f"cannot read {what} ({exc.strerror or exc})", file=p) from None
    if stat.S_ISREG(st.st_mode):
        return p
    kind = ("a folder" if stat.S_ISDIR(st.st_mode) else "a FIFO/named pipe" if stat.S_ISFIFO(st.st_mode)
            else "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode)
            else "a socket" if stat.S_ISSOCK(st.st_mode) else "not a file")
    raise InputError(f"cannot read {what}: not a regular file ({kind})", file=p)
