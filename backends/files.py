"""Atomic file output for the backends: the one implementation lives in prsc.files."""

from prsc.files import atomic_copy, atomic_text, atomic_write, atomic_write_tree, write_bytes

__all__ = ["atomic_copy", "atomic_text", "atomic_write", "atomic_write_tree", "write_bytes"]
