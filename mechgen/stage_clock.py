"""Seconds of a build's inner stages, for :class:`mechgen.pipeline.BuildReport`.

The pipeline times its outer stages itself (derive, lower, emit, build). Inside them, ``declare`` (calling the
model's declared energies and specialising them: part of ``derive``), ``rewrite`` (the Horner rewrites) and
``cse`` (sympy's common-subexpression elimination, both part of ``lower``) are timed where they run, with
:func:`timed_stage`, into the dict that :func:`collecting` names for the current build. Outside a build (a
test calling :func:`mechgen.codegen.rewrite.optimise` directly) nothing is recorded. The dict is per context
(contextvars), so builds in other threads do not mix.
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from contextvars import ContextVar

_SECONDS: ContextVar[dict | None] = ContextVar("mechgen_stage_seconds", default=None)


@contextmanager
def collecting(seconds: dict):
    """Inner stages timed inside the block add their seconds to ``seconds``."""
    token = _SECONDS.set(seconds)
    try:
        yield seconds
    finally:
        _SECONDS.reset(token)


@contextmanager
def timed_stage(name: str):
    """Add the block's wall time to stage ``name`` of the build being collected (if any)."""
    seconds = _SECONDS.get()
    if seconds is None:
        yield
        return
    start = time.perf_counter()
    try:
        yield
    finally:
        seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - start
