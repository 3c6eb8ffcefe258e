"""Offline synthesis: discounted LQR gains (and, later, Theorem 4.1 tables and J^N)."""
