"""Learning across a tool family: ANFIS (:mod:`toolpoint.learning.anfis`), the paper's metrics
(:mod:`toolpoint.learning.metrics`), figures (:mod:`toolpoint.learning.figures`)."""
