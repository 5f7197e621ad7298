"""Structural dynamics of the spindle–holder–tool assembly.

Assembly description (:mod:`.assembly`) → exact Timoshenko segments
(:mod:`.beam`) → component end receptances (:mod:`.components`) → receptance
coupling through complex joints (:mod:`.coupling`) → the spindle–holder
subassembly (:mod:`.subassembly`, or from a blank by :mod:`.inverse_rcsa`) → the
tool-point FRF (:mod:`.model`). :mod:`.fe` is an independent full-assembly
finite-element check; :mod:`.modal` a common-pole modal fit (natural
frequencies, damping, modal constants; the denoiser of inverse RCSA).
"""
