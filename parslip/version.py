"""parslip's version: one definition, below every layer (provenance in every output file)."""
__version__ = "0.1.0"
