"""Keep freed memory in the process: NumPy's large temporaries without a page fault per page.

glibc's ``malloc`` serves a block above its mmap threshold (128 KiB at start, raised up to 32 MiB as such blocks
are freed) with a fresh ``mmap`` and gives it back on ``free``; a heap top above its trim threshold is handed back
too. Every such block is then mapped again, page by page, on its first touch. toolpoint's forward models make
megabytes of temporaries per call — ``limit_at_speeds`` an (S, 2, F) complex array per block of 100 samples, the
semi-discretisation its monodromy products — thousands of times per ``update``, so on a virtual machine, where a
page fault is dear, the kernel's share was a fifth of the time: one EM12-60 update after six cuts took 6.7–8.1 s
system CPU of 31.5–39.3 s, with 2.07–2.09 million minor page faults; with :func:`keep_freed_memory` 0.1–0.2 s of
26.1–32.1 s, 16,000 faults, the same result to the bit (2026-12-02, 2-core AMD EPYC VM without AVX-512,
``docs/design/shop.md``, *Freed memory kept*).

The ``toolpoint`` command calls :func:`keep_freed_memory` on start; a notebook or script may call it once.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import sys

# mallopt(3) parameters (glibc's malloc.h)
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3
MIB = 1 << 20


def keep_freed_memory(mmap_threshold: int = 32 * MIB, trim_threshold: int = 256 * MIB,
                      top_pad: int = 16 * MIB) -> bool:
    """Let glibc's ``malloc`` keep freed blocks for reuse instead of returning them to the kernel.

    Sets ``M_MMAP_THRESHOLD`` (blocks above it still get their own mapping, given back on free; setting it also
    stops glibc's own moving of it), ``M_TRIM_THRESHOLD`` (free memory at the heap's top kept up to this) and
    ``M_TOP_PAD`` (extra asked of the kernel at each growth). The process then holds up to ``trim_threshold`` of
    freed memory between calls; results do not change, only where their memory comes from.

    Parameters
    ----------
    mmap_threshold, trim_threshold, top_pad : int
        Bytes (defaults 32 MiB, 256 MiB, 16 MiB).

    Returns
    -------
    bool
        True where glibc took all three settings; False elsewhere (another C library, macOS, Windows): nothing
        changed there.

    Examples
    --------
    >>> from toolpoint.memory import keep_freed_memory
    >>> keep_freed_memory() in (True, False)
    True
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # musl and others have no mallopt: their allocator stays as it is
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    ok = [mallopt(_M_MMAP_THRESHOLD, int(mmap_threshold)), mallopt(_M_TRIM_THRESHOLD, int(trim_threshold)),
          mallopt(_M_TOP_PAD, int(top_pad))]
    return all(r == 1 for r in ok)
