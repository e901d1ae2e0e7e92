"""Built-in descriptions of machines without gears (``type = "shafts"``; TOML files shipped
as package data)."""
