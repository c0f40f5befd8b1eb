"""One run: the loops (simulation, compiled), the composition root (experiment), the
result and its metrics, verdicts and properties.
"""
