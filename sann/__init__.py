"""SANN: a Soar production system, plan fusion and graspability networks (Zuo et al.)."""

__version__ = "0.1.0"
