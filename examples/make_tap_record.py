"""Regenerate examples/tap_record.csv: a SYNTHETIC impact record (not a measurement).

    python examples/make_tap_record.py

The virtual impact test of toolpoint.io.virtual_tap, modelled on the lab test of issue 20 (end mill in a collet
holder: modes 1071 / 1981 / 2607 Hz, ζ 3.7 / 4.1 / 2.1 %, |H| ≈ 6.8e-7 m/N at the first peak, close x/y twins),
steel tip, three hits 70 ms apart, 51.2 kHz, 24-bit, with the chain's offset, drift, high-pass, hum and noise.
"""

from pathlib import Path

from toolpoint.io.virtual_tap import lab_like_tap, write_record

OUT = Path(__file__).resolve().parent / "tap_record.csv"

if __name__ == "__main__":
    rec = lab_like_tap(seed=2026, hits=3, spacing_s=0.07)
    write_record(OUT, rec, note="regenerate: python examples/make_tap_record.py (seed 2026)")
    print(f"wrote {OUT} ({OUT.stat().st_size / 1e3:.0f} kB, {rec.time_s.size} samples)")
