"""Scenes: the keys (schema), reading a TOML scene with overrides (load), and the numbers a scene implies (derive)."""
