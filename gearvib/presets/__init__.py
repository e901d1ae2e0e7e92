"""Built-in gear-set presets (TOML files shipped as package data)."""
