"""Records of a cut: microphone audio, accelerometer or displacement time histories → one channel of samples.

Formats (by extension, or by the first bytes: audio renamed or without its suffix is audio; MATLAB ``.mat``, HDF5
and TDMS files are refused saying how to export the signal, and audio libsndfile does not read — a phone's M4A / AAC /
3GP / AMR, WMA, WebM — saying how to convert it):

* audio ``.wav .flac .ogg .mp3`` (and whatever else libsndfile reads: ``.aiff``, ``.au``) through the
  ``soundfile`` package (libsndfile ≥ 1.1 for MP3; the wheels of soundfile ≥ 0.12.1 bundle 1.2);
* ``.uff .unv .uf``: universal files, datasets 58 of function type 1 (time response); the sampling
  step is the abscissa increment;
* anything else: a text table (comma, semicolon with the decimal comma, tab or space separated, optional header,
  ``#``/``%`` comments). Several columns: the first is time — in s, or in ms or µs where the header says so
  (``Time (ms)``) — increasing in equal steps to the digits it was printed with (the rate follows from the first
  and last rows), the others are channels; one column: samples, and the rate must be given.

The channel is chosen by ``channel`` (0-based among the signal columns / audio channels); without it
a multichannel audio file is averaged (a stereo microphone's two channels hear the same cut) and a
table must have one signal column.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["CutRecord", "read_cut_record", "AUDIO_SUFFIXES"]

AUDIO_SUFFIXES = (".wav", ".flac", ".ogg", ".oga", ".opus", ".mp3", ".aif", ".aiff", ".aifc", ".au", ".snd", ".caf",
                  ".w64", ".rf64")
_UFF_SUFFIXES = (".uff", ".unv", ".uf")


@dataclass(frozen=True)
class CutRecord:
    """One channel of a record of a cut.

    Attributes
    ----------
    samples : ndarray, shape (T,)
        The signal (audio: full scale ±1; tables and UFF: their unit, e.g. m/s² or m).
    rate_hz : float
        Sampling rate, Hz.
    source : str
        The file it came from.
    channel : str
        Which channel: ``"mean of 2"``, ``"0"``, …
    full_scale : float or None
        The clipping level of the recording (1.0 for audio read as float), None when unknown.
    warnings : tuple of str
        What the reader chose and why (a stereo file whose channels cancel in a band when averaged: one channel
        read instead).
    """

    samples: np.ndarray
    rate_hz: float
    source: str
    channel: str
    full_scale: float | None = None
    warnings: tuple = ()

    @property
    def duration_s(self) -> float:
        """Length of the record, s."""
        return self.samples.size / self.rate_hz


def read_cut_record(path: str | os.PathLike, *, rate_hz: float | None = None, channel: int | None = None) -> CutRecord:
    """Read a record of a cut (audio, UFF58 time history or text columns).

    Parameters
    ----------
    path : str or path-like
        The file.
    rate_hz : float, optional
        Sampling rate, Hz: required for a one-column table; for other files it must agree
        with the file's own rate (within 0.1 %) when given.
    channel : int, optional
        0-based channel (audio channel, table signal column, UFF time history).

    Returns
    -------
    CutRecord

    Raises
    ------
    InputError
        One line naming the file and the field (``rate_hz``, ``channel``, ``time_s``, ``data``, …).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "acc.csv"
    >>> _ = p.write_text("time_s,acc\\n0,0.1\\n0.001,0.2\\n0.002,-0.1\\n")
    >>> r = read_cut_record(p)
    >>> r.rate_hz, r.samples.tolist()
    (1000.0, [0.1, 0.2, -0.1])
    """
    p = Path(path)
    if p.is_dir():
        raise InputError("is a folder, not a record", file=p)
    if not p.exists():
        raise InputError("file not found", file=p)
    from .table import check_regular_file

    check_regular_file(p, what="record")  # before the first bytes are read: a FIFO would block for ever
    suffix = p.suffix.lower()
    kind = _sniff(p)
    if kind is None and suffix in _AUDIO_NOT_READ_SUFFIXES:
        kind = _AUDIO_NOT_READ_SUFFIXES[suffix]
    if kind in _AUDIO_NOT_READ:
        raise InputError(f"{_AUDIO_NOT_READ[kind]}: toolpoint reads audio as WAV, FLAC, OGG, MP3, AIFF or CAF; "
                         f"convert it (ffmpeg -i {p.name} {p.stem}.wav) or set the recorder to WAV", file=p,
                         field="data")
    if kind in _NOT_READ:
        raise InputError(f"{_NOT_READ[kind]}: toolpoint reads audio (WAV, FLAC, OGG, MP3, AIFF, CAF), text columns "
                         "and UFF58; export the signal as one of those (MATLAB: audiowrite, or "
                         "writematrix([t(:) x(:)], 'cut.csv'))", file=p, field="data")
    if suffix in AUDIO_SUFFIXES or kind == "audio":  # a recorder's file renamed or without its suffix
        rec = _read_audio(p, channel)
    elif suffix in _UFF_SUFFIXES:
        rec = _read_uff(p, channel)
    else:
        rec = _read_table(p, channel, rate_hz)
    if rate_hz is not None:
        if not (np.isfinite(rate_hz) and rate_hz > 0):
            raise InputError(f"must be a finite rate > 0 Hz, got {rate_hz!r}", file=p, field="rate_hz")
        if abs(rec.rate_hz / rate_hz - 1) > 1e-3:
            raise InputError(f"the file says {rec.rate_hz:.6g} Hz, the command line {rate_hz:.6g} Hz", file=p,
                             field="rate_hz")
    if rec.samples.size == 0:
        raise InputError("no samples", file=p, field="data")
    if not np.all(np.isfinite(rec.samples)):
        k = int(np.flatnonzero(~np.isfinite(rec.samples))[0])
        raise InputError(f"sample {k} is not finite", file=p, field="data")
    return rec


_NOT_READ = {"mat": "a MATLAB .mat file", "hdf5": "an HDF5 file (MATLAB -v7.3, or a DAQ's)",
             "tdms": "a LabVIEW TDMS file"}
# audio that libsndfile does not read, mostly what phones record: refused saying how to convert it, where it had been
# read as a text table ("no data rows") or as "not a UTF-8 text file"
_AUDIO_NOT_READ = {"mp4": "an MP4 / M4A / 3GP container (a phone's recorder: AAC or ALAC audio)",
                   "aac": "raw AAC audio (ADTS)", "amr": "AMR speech audio (a phone's voice recorder)",
                   "asf": "a Windows Media (WMA / ASF) file", "mkv": "a WebM / Matroska file (a browser's recorder)"}
_AUDIO_NOT_READ_SUFFIXES = {".m4a": "mp4", ".m4b": "mp4", ".mp4": "mp4", ".mov": "mp4", ".3gp": "mp4",
                            ".3g2": "mp4", ".aac": "aac", ".amr": "amr", ".wma": "asf", ".asf": "asf",
                            ".webm": "mkv", ".mka": "mkv", ".mkv": "mkv"}


def _sniff(p: Path) -> str | None:
    """What the file's first bytes say it is: ``audio`` (RIFF/WAVE and its large forms RF64 and Wave64, FLAC, Ogg,
    MP3, AIFF, Apple's CAF, AU), or a
    container toolpoint does not read (``mat``, ``hdf5``, ``tdms``; audio ``mp4``, ``aac``, ``amr``, ``asf``,
    ``mkv``); None: anything else (text, UFF)."""
    try:
        with open(p, "rb") as fh:
            head = fh.read(128)
    except OSError:
        return None  # the reader that opens it names the reason
    if head[:4] in (b"RIFF", b"RF64", b"BW64") and head[8:12] == b"WAVE" \
            or head[:4] in (b"fLaC", b"OggS", b"ID3\x03", b"ID3\x04", b"caff", b".snd") \
            or head[:16] == bytes.fromhex("72696666 2e91cf11 a5d628db 04c10000") \
            or head[:4] == b"FORM" and head[8:12] in (b"AIFF", b"AIFC") \
            or len(head) > 1 and head[0] == 0xFF and head[1] & 0xE6 == 0xE2:  # an MPEG layer III frame (no ID3
        # tag); not FF FE, the byte-order mark of a UTF-16 text file (a spreadsheet's "Unicode text" export)
        return "audio"
    if head.startswith(b"MATLAB 5.0 MAT-file") or head.startswith(b"MATLAB 7.3 MAT-file"):
        return "hdf5" if head.startswith(b"MATLAB 7.3") else "mat"
    if head.startswith(b"\x89HDF\r\n\x1a\n"):
        return "hdf5"
    if head.startswith(b"TDSm"):
        return "tdms"
    if head[4:8] == b"ftyp":  # ISO base media: M4A, MP4, MOV, 3GP
        return "mp4"
    if len(head) > 1 and head[0] == 0xFF and head[1] & 0xF6 == 0xF0:  # an ADTS frame: sync, layer 00
        return "aac"
    if head.startswith(b"#!AMR"):
        return "amr"
    if head.startswith(bytes.fromhex("3026b2758e66cf11a6d900aa0062ce6c")):
        return "asf"
    if head.startswith(b"\x1a\x45\xdf\xa3"):
        return "mkv"
    return None


def _pick(data: np.ndarray, channel: int | None, p: Path, what: str, names=None) -> tuple[np.ndarray, str]:
    """One channel of ``data`` (T, C): the given one, or the mean of all (audio) / the only one; ``names`` (C, the
    table's header) name it in the result and list the choice in the refusal."""
    n = data.shape[1]

    def label(k):
        return f"{k} ({names[k]})" if names and names[k] else str(k)

    if channel is None:
        if n == 1:
            return data[:, 0], label(0)
        if what == "audio":
            mean = data.mean(axis=1, dtype=float)
            # channels in opposite polarity (a swapped lead, an interface's inverted input) cancel in the mean: the
            # real recording with one channel inverted averaged to its quantisation residue and was refused as
            # "clipped at 1.5e-05". Said as it is, with what to give instead
            each = float(np.mean([np.var(data[:, k], dtype=float) for k in range(n)]))  # a channel at a time
            if each > 0 and float(np.var(mean)) < 0.1 * each:
                raise InputError(f"the {n} audio channels cancel when averaged (the mean keeps "
                                 f"{100 * np.var(mean) / each:.2g} % of their power: one is inverted?); choose one "
                                 f"with --channel (0..{n - 1})", file=p, field="channel")
            return mean, f"mean of {n}"
    k = channel_index(n, channel, p, what, names, kind="channels" if what == "audio" else "signal columns")
    return data[:, k], label(k)


def channel_index(n: int, channel: int | None, p, what: str, names=None, kind: str = "signal columns") -> int:
    """The channel of ``n`` ``kind`` (``what`` holds them) to read: the given one (0-based), or the only one;
    several without a choice are refused listing them (``names``, e.g. the header's), as is a channel that does not
    exist."""
    if channel is None:
        if n == 1:
            return 0
        raise InputError(f"{n} {kind}: choose one with --channel "
                         + (f"({', '.join(f'{k}: {names[k]}' for k in range(n))})" if names else f"(0..{n - 1})"),
                         file=p, field="channel")
    if not (0 <= channel < n):
        raise InputError(f"channel {channel} does not exist ({what} has {n} {kind}: 0..{n - 1})", file=p,
                         field="channel")
    return channel


def _read_audio(p: Path, channel: int | None) -> CutRecord:
    import soundfile as sf

    from .table import check_regular_file

    check_regular_file(p, what="record")
    try:
        data, rate = sf.read(p, dtype="float32", always_2d=True)
    except (sf.LibsndfileError, RuntimeError, TypeError, ValueError) as err:
        raise InputError(f"cannot read audio: {' '.join(str(err).split())}", file=p, field="data") from None
    except OSError as err:
        raise InputError(f"cannot read audio: {err.strerror or err}", file=p, field="data") from None
    # one channel in float64, not all: 10 min of 192 kHz stereo is 1.8 GB in float64
    x, ch = _pick(data, channel, p, "audio")
    warns = ()
    if channel is None and data.shape[1] > 1:
        band = _mean_cancels(data, x, float(rate))
        if band is not None:  # read the loudest channel (in the band the check read) instead, and say so
            keep, lo, hi, k = band
            x, ch = data[:, k], f"{k} (the loudest; the mean of {data.shape[1]} cancels at {lo:.0f}–{hi:.0f} Hz)"
            warns = (f"the mean of the {data.shape[1]} channels keeps {100 * keep:.0f} % of their power at "
                     f"{lo:.0f}–{hi:.0f} Hz (microphones apart: the sound reaches them at different times and "
                     f"cancels there when averaged); channel {k}, the loudest, was read (`cut --channel` picks "
                     "another)",)
    low = _low_bit_rate(p, sf)
    if low is not None:
        warns = (*warns, low)
    return CutRecord(np.asarray(x, float), float(rate), os.fspath(p), ch, full_scale=1.0, warnings=warns)


_LOSSY = {"MPEG_LAYER_I": "MP1", "MPEG_LAYER_II": "MP2", "MPEG_LAYER_III": "MP3", "VORBIS": "Vorbis", "OPUS": "Opus"}
_LOW_KBPS = 80.0
"""A lossy file's mean bit rate under which the reader warns, kbit/s. At a low rate the perceptual coder's artefacts
stand 22–27 dB under the strongest harmonic, where weak chatter's tooth-passing aliases are judged. Measured on
simulated microphone records (``docs/design/shop.md``, *A phone's voice note*): of 576 grid records, Opus at 34
kbit/s (a messenger's voice note) called 30 stable cuts chatter, against 0 uncompressed, at 72 kbit/s 0 (one verdict
changed), at 136 kbit/s none changed; of 896, MP3 at 48 kbit/s 6 and Vorbis at 65 kbit/s 4 (and 7 chattering cuts
missed), MP3 at 91 kbit/s 1. The real recording is an MP3 of 128 kbit/s."""


def _low_bit_rate(p: Path, sf) -> str | None:
    """A warning for an audio file coded lossily at under :data:`_LOW_KBPS` (its mean bit rate, from its size and
    duration, the container's few bytes included), else None."""
    try:
        info = sf.info(p)
    except (sf.LibsndfileError, RuntimeError, TypeError, ValueError, OSError):
        return None
    codec = _LOSSY.get(info.subtype)
    if codec is None or not info.duration > 0:
        return None
    kbps = p.stat().st_size * 8 / info.duration / 1000
    if kbps >= _LOW_KBPS:
        return None
    return (f"coded as {codec} at {kbps:.0f} kbit/s: a perceptual coder's artefacts can pass for weak chatter "
            "(simulated records coded at 34–65 kbit/s: 0.8–5.4 % more verdicts wrong, most of them stable cuts "
            "called chatter); record WAV or FLAC, or at 128 kbit/s or more")


_CANCEL_KEEP = 0.25
"""The mean of a stereo file's channels that keeps less than this share of their power in a third-octave band has
them cancel there. Channels that do not correlate keep 1/2 (of two), in phase 1, the real recording's (two
microphones side by side) 0.94–1.0 in every band; two microphones 15 cm apart hear a source off their axis up to
0.45 ms apart, and their mean has a notch at 1/(2τ) ≈ 1.1 kHz: in the chatter band."""


def _mean_cancels(data, mean, rate) -> tuple | None:
    """(share kept, band's low Hz, high Hz, the loudest channel over the bands) of the third-octave band (160 Hz –
    min(8 kHz, 0.45 rate)) where the channels' mean keeps the least of their mean power, when that share is under
    :data:`_CANCEL_KEEP`; else None. The channels' powers come from the same spectra: no float64 copy of them all.

    Why: averaging two microphones a few cm apart comb-filters the sound (notches at odd multiples of 1/(2τ), τ their
    delay): the real recording's channels, one of them delayed by 0.47 ms, averaged to a record whose 1067 Hz chatter
    was notched out — read as chatter at its second harmonic, 2135 Hz, and its air as cutting (2026-12-06)."""
    nper = int(min(8192, max(256, 2 ** round(np.log2(0.1 * rate)))))
    if data.shape[0] < 2 * nper:
        return None
    f, p_mean = _welch(mean, rate, nper)  # bands from 160 Hz: no offset reaches them
    _, p_ch = _welch(data, rate, nper)  # (F, C), float32 as read
    p_each = p_ch.mean(axis=1)
    worst = None
    centre = 160.0
    while centre * 2 ** (1 / 6) <= min(8000.0, 0.45 * rate):
        lo, hi = centre * 2 ** (-1 / 6), centre * 2 ** (1 / 6)
        sel = (f >= lo) & (f < hi)
        if sel.any() and p_each[sel].sum() > 0:
            keep = float(p_mean[sel].sum() / p_each[sel].sum())
            if worst is None or keep < worst[0]:
                worst = (keep, lo, hi)
        centre *= 2 ** (1 / 3)
    if worst is None or worst[0] >= _CANCEL_KEEP:
        return None
    inband = (f >= 160.0 * 2 ** (-1 / 6)) & (f <= min(8000.0, 0.45 * rate))
    return (*worst, int(np.argmax(p_ch[inband].sum(axis=0))))


def _welch(x, rate, nper, frames=128):
    """:func:`scipy.signal.welch` along axis 0 (Hann, half overlap, no detrending), ``frames`` frames at a time: all at
    once it holds each frame twice over, 1.8 GB for 10.5 min of 44.1 kHz stereo. The mean of the chunks' means, each
    weighted by its frames, is the mean over all frames."""
    from scipy.signal import welch

    hop = nper // 2
    n = 1 + (x.shape[0] - nper) // hop
    acc = None
    for a in range(0, n, frames):
        b = min(n, a + frames)
        f, p = welch(x[a * hop:(b - 1) * hop + nper], rate, nperseg=nper, detrend=False, axis=0)
        acc = p * (b - a) if acc is None else acc + p * (b - a)
    return f, acc / n


def _read_uff(p: Path, channel: int | None) -> CutRecord:
    from .frf_files import _uff_headers

    uff, sets, heads = _uff_headers(p)
    th = [s for s, h in zip(sets, heads) if h.get("func_type") == 1]
    if not th:
        types = ", ".join(str(h.get("func_type")) for h in heads)
        raise InputError(f"no time history (dataset 58 of function type 1; function types here: {types})",
                         file=p, field="func_type")
    k = 0 if channel is None and len(th) == 1 else channel
    if k is None:
        raise InputError(f"{len(th)} time histories: choose one with --channel (0..{len(th) - 1})", file=p,
                         field="channel")
    if not (0 <= k < len(th)):
        raise InputError(f"channel {k} does not exist ({len(th)} time histories: 0..{len(th) - 1})", file=p,
                         field="channel")
    try:
        ds = uff.read_sets(th[k])
    except Exception as exc:  # pyuff raises bare Exception
        raise InputError(f"dataset {th[k]} cannot be read ({exc})", file=p, field="data") from None
    if np.iscomplexobj(ds["data"]):
        raise InputError("time history must be real (ordinate data type 2 or 4)", file=p, field="ord_data_type")
    t = np.asarray(ds["x"], float)
    if t.size < 2 or not np.all(np.diff(t) > 0):
        raise InputError("abscissa must increase", file=p, field="abscissa_inc")
    return CutRecord(np.asarray(ds["data"], float), float(1.0 / np.mean(np.diff(t))), os.fspath(p), str(k))


def _read_table(p: Path, channel: int | None, rate_hz: float | None) -> CutRecord:
    from .frf_files import _is_number, _read_text, column_names, drop_empty_columns, numeric_lines

    text, _ = _read_text(p)
    rows, lines = [], []
    width = None
    numbered = list(numeric_lines(text))
    for n, cells in numbered:
        if width is None:
            width = len(cells)
        if len(cells) != width:
            raise InputError(f"line {n}: expected {width} columns, found {len(cells)}", file=p, field="columns")
    if not numbered:
        raise InputError("no data rows (no line of numbers; cells split at ';', ',' or white space)", file=p,
                         field="data")
    # a column empty in every row is no channel (a LabVIEW export's Comment column): dropped, and its name with it
    names = column_names(text, numbered[0][0], width)
    kept, keep = drop_empty_columns(numbered)
    for n, cells in kept:
        for j, c in enumerate(cells):
            if not _is_number(c):
                raise InputError(f"line {n}: {c!r} is not a number", file=p, field=f"column {keep[j]}")
        rows.append(cells)
        lines.append(n)
    a = np.array(rows, dtype=float)
    names = [names[j] for j in keep] if names else None
    if a.shape[1] == 1:
        if rate_hz is None:
            raise InputError("one column of samples: give the sampling rate (--rate HZ)", file=p, field="rate_hz")
        x, ch = a[:, 0], "0"
        return CutRecord(x, float(rate_hz), os.fspath(p), ch)
    unit, scale = _time_unit(text, lines[0])
    t = a[:, 0] * scale
    _check_time(t, lines, p, unit, scale)
    x, ch = _pick(a[:, 1:], channel, p, "the table", names=names[1:] if names else None)
    return CutRecord(x, float((t.size - 1) / (t[-1] - t[0])), os.fspath(p), ch)


def _time_unit(text: list[str], first: int) -> tuple[str, float]:
    """The time column's unit from the header line above the data (``Time (ms)``, ``t [us]``, ``time_ms``, or a
    DAQ's units row ``ms;g``; default s) and its factor to s; ``first`` is the first data line's number (1-based)."""
    from .frf_files import column_unit, header_cells

    head = header_cells(text, first)[:1]
    u = column_unit(head[0][0]) if head and head[0] else None
    return (u[0], u[2]) if u is not None and u[1] == "time" else ("s", 1.0)


def _check_time(t: np.ndarray, lines: list[int], p: Path, unit: str, scale: float) -> None:
    """The time column must increase in equal steps, to the digits it was printed with: a DAQ's export at 25.6 kHz
    with the time to 1 µs has steps of 39 and 40 µs. Refused: a step ≤ 0 (too few digits, or not a time), and a step
    more than half a step off the median step (samples missing or doubled)."""
    hint = " (one column of samples needs --rate instead)"
    if t.size < 2:
        raise InputError("first column must be time, increasing in equal steps: one row" + hint, file=p,
                         field="time_s")
    d = np.diff(t)
    bad = np.flatnonzero(~(d > 0))
    if bad.size:
        k = int(bad[0]) + 1
        raise InputError(f"line {lines[k]}: the time ({t[k] / scale:.9g} {unit}) does not increase: "
                         "printed with too few digits for the sampling rate, or not a time column" + hint, file=p,
                         field="time_s")
    dt = float(np.median(d))
    bad = np.flatnonzero(np.abs(d / dt - 1) > 0.5)
    if bad.size:
        k = int(bad[0]) + 1
        raise InputError(f"line {lines[k]}: a time step of {d[k - 1]:.6g} s where the steps are {dt:.6g} s: samples "
                         "missing or doubled?" + hint, file=p, field="time_s")
