"""jinja2 environment for the backend templates (no logic in templates, StrictUndefined)."""
from __future__ import annotations

from functools import lru_cache

import jinja2


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    """The shared template environment (templates/ beside this module)."""
    return jinja2.Environment(loader=jinja2.PackageLoader("mechgen.codegen", "templates"),
                              undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=False,
                              keep_trailing_newline=True, autoescape=False)


def render(name: str, **context: object) -> str:
    """Render template ``name`` with ``context``."""
    return environment().get_template(name).render(**context)
