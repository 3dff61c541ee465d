"""Reading rule files: the grammar, the parse tree's transformer, load-time checks."""
