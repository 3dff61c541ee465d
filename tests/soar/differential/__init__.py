"""Differential tests: our Soar engine against the real Soar 9.6 kernel."""
