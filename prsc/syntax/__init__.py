"""The .prs front end's first stage: source text -> AST with spans (no semantics)."""

from prsc.syntax.parser import decode_source, decode_text, parse_file, parse_source

__all__ = ["decode_source", "decode_text", "parse_file", "parse_source"]
