"""Test cuts close the loop: listen to a cut, update the stability lobes, choose the next cut.

* :func:`analyse_cut` — chatter detection from a record of a cut (microphone, accelerometer,
  displacement): spindle and tooth-passing harmonics removed, chatter frequency, verdict per segment,
  Harmonizer-style speed (:mod:`toolpoint.shop.detect`).
"""

from .detect import CutAnalysis, CutSegment, analyse_cut, check_record, harmonizer_rpm, plot_cut

__all__ = ["CutAnalysis", "CutSegment", "analyse_cut", "check_record", "harmonizer_rpm", "plot_cut"]
