"""Matching productions against working memory.

A reader's map, in the order a WME travels:

- ``symbols``: Soar's symbol equality, total order and relational tests.
- ``variables``: which variables a test or condition binds or mentions.
- ``matches``: what a matcher reports (``Match``) and the changes since the last look.
- ``oracle``: the brute-force matcher, obviously correct, the Rete's test oracle.
- ``rete``: the Rete (Doorenbos 1995), the matcher the agent runs; built from ``plan``
  (what a condition compiles to), ``join_order`` (which condition joins next) and
  ``build`` (making and removing nodes).
- ``alpha``: alpha memories and the network that finds a WME's memories.
- ``tokens``: partial matches, the hash indices that file them, a WME's record.
- ``nodes``: join, negative, NCC and partner nodes; ``runs``: runs of independent
  conditions joined as one node; ``query_ncc`` and ``query``: conjunctive negations
  answered by a search; ``production_node``: the matches.
- ``templates``: the lines of generated code the nodes' activations share.  Every
  generated function has a plain Python twin beside it (``SANN_PLAIN=1`` runs those;
  ``sann.soar.codegen`` runs the generated source and shows it to tracebacks).
- ``reorder``, ``kernel_order``, ``kernel_prefix``: the Soar kernel's own order of
  conditions and of making matches, which our firing order copies.
"""
