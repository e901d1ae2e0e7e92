"""Parametric-instability tools: Floquet analysis, Mathieu-type theory candidates, peak labels."""
