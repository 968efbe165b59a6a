"""The papers' protocols as reusable scenario functions."""

from .static_run import StaticRunResult, run_static

__all__ = ["StaticRunResult", "run_static"]
