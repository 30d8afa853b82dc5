"""Studies that run scenes and read them back: which runs, running or reusing them, scoring what they show.

Unlike ``parslip.analysis``, which only reads runs, a study starts them (through one runner function per
study) and may import analysis, scene, io and the run API.
"""
