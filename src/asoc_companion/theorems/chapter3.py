"""Checks of the numbered statements of Chapter 3 (Thm. 3.1 to Thm. 3.33)."""

STATEMENTS = []
