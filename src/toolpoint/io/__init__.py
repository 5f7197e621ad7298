"""Files in and out: FRF files (CSV, whitespace text, UFF58, CutPro), the TOML schema reader, atomic writes.

Lengths are in mm at this boundary; everything returned is SI.
"""
