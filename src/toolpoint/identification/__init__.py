"""Identification of joint parameters from measured FRFs.

Parameters and bounds (:mod:`.params`) → objective (:mod:`.objective`) →
optimisers (:mod:`.optim`: GA, SA, PSO, DE, hybrid) → confidence intervals
(:mod:`.uncertainty`) → :func:`.identify.identify`.
"""
