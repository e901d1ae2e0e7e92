"""Example study recipes and sweeps shipped with gearvib (TOML files as package data).

``gearvib example`` lists them, ``gearvib example NAME > study.toml`` prints one to start from;
:func:`gearvib.config.list_examples` / :func:`gearvib.config.example_text` in Python. They name
presets only, so a printed copy works from any folder.
"""
