"""Soar 9.6's explanation-based chunking: backtrace a result, variablize, add the rule."""

from .backtrace import Explanation
from .learn import Chunker

__all__ = ["Chunker", "Explanation"]
