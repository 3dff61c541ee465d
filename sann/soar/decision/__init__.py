"""The decision cycle, one concept a module, in the order they build on one another.

- ``preference_semantics``: how a slot's preferences choose its values (or an impasse), and
  the exploration policies of an indifferent choice;
- ``agent_state``: the data an agent keeps while it runs, and the operations every phase
  shares (trace output, retraction queues, working-memory indexes);
- ``working_memory``: adding and removing WMEs, and what their leaving sets off;
- ``firing_order``: the order the kernel's Rete makes and loses matches in, which decides
  the order rules fire and retract in;
- ``matches``: the matcher's new and lost matches queued at their goals;
- ``results``: a substate's results, their justifications, the goal dependency set;
- ``firing``: firing instantiations, retracting them, asserting their preferences;
- ``wm_phase``: the working-memory phase, changed slots become WME changes;
- ``substates``: impasses make substates; removing one takes everything below it;
- ``decide``: the decision phase (the operator slots) and the goal stack's consistency;
- ``cycle``: the phases themselves, input, propose, decide, apply, output.

``sann.soar.agent.Agent`` is the public face: it holds the state (``AgentState``) and calls
``cycle.run_phase``.
"""
