"""Reading rule files: the grammar (``soar.lark``), the parser and its post-lexer (`parser`),
the transformer from grammar rules to production dataclasses (`transformer`), the kernel's
rewriting of conditions and names of fresh variables (`normalise`), the load-time checks of
the right-hand side (`actions`), the checks of whole productions (`checks`) and Lark's errors
in words, with file:line:column (`errors`).
"""
