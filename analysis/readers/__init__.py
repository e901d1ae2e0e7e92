"""Readers that turn measured files into the common CF-annotated Dataset layout."""
