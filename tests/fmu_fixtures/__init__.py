"""Tiny pythonfmu slaves used only by the master's tests, and their build step."""
