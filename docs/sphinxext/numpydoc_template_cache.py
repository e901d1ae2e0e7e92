"""Sphinx extension: numpydoc's docstring template compiled once per build.

numpydoc (1.x) makes a new Jinja environment, and so compiles its ``numpydoc_docstring.rst``
template again, for every object it renders (about 1,800 times for this API reference, a tenth
of the build's time). This extension gives numpydoc an environment class that keeps the
compiled template of each loader type and name for the rest of the build. The output is
unchanged; if numpydoc's internals change, the extension does nothing.
"""

from __future__ import annotations

from typing import Any


def setup(app: Any) -> dict[str, Any]:
    try:
        from numpydoc import docscrape_sphinx
    except ImportError:
        return {"parallel_read_safe": True}
    base = getattr(docscrape_sphinx, "SandboxedEnvironment", None)
    if base is None or getattr(base, "_gearvib_cached", False):
        return {"parallel_read_safe": True}

    compiled: dict[tuple[type, str], Any] = {}

    class CachedEnvironment(base):  # type: ignore[misc, valid-type]
        _gearvib_cached = True

        def get_template(self, name: Any, *args: Any, **kwargs: Any) -> Any:
            if args or kwargs or not isinstance(name, str):
                return super().get_template(name, *args, **kwargs)
            key = (type(self.loader), name)
            if key not in compiled:
                compiled[key] = super().get_template(name)
            return compiled[key]

    docscrape_sphinx.SandboxedEnvironment = CachedEnvironment
    return {"parallel_read_safe": True}
