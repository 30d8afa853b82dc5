"""The studies of the slip-weakening interface (docs/studies/weakening.md), a module each."""
