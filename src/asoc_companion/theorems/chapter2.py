"""Checks of the numbered statements of Chapter 2 (Lemma 2.1 to Prop. 2.7, and the kernel claim of Sec. 2.6.3)."""

STATEMENTS = []
