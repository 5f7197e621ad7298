"""Learning across a tool family: ANFIS (:mod:`.anfis`), the paper's metrics (:mod:`.metrics`), figures
(:mod:`.figures`)."""
