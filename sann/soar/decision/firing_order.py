"""The order the kernel's Rete makes and loses matches in, which is the order rules fire
and retract in.

The kernel's Rete makes a match when the last of its WMEs enters (a batch of WME changes
enters newest first, its removals after its additions), at a join whose place among its
alpha memory's joins depends on when the join was last linked (a join whose parent memory
empties is unlinked, and relinked at the tail when a token comes). ``rete.KernelOrder``
keeps the kernel's node tree; this module turns a match into a sort key from it
(``kernel_key``), sorts a batch of new matches (``batch_sorted``) and lost ones
(``found_order``), and keeps the link records (``JoinLink``) up to date (``check_links``).
"""

from __future__ import annotations

from typing import Final

from ..instantiation import Instantiation
from ..memory import WME, Symbol
from ..production import Condition, Const
from ..rete import _wme_fits, equality_vars, prefix_token
from .agent_state import AgentState, JoinLink, vkey

# The fields of a join's *place*, the tuple ``rete.KernelOrder.add`` makes per written
# positive condition (``Final``: mypyc compiles ``place[BORN]`` as ``place[2]``).
#: the condition's alpha memory: 2 if its attribute is a constant, | 4 if its value is
MASK: Final = 0
#: the written indexes of the positive conditions above the condition's join
BEFORE: Final = 1
#: the timetag when the join was made (or relinked at init-soar: 0)
BORN: Final = 2
#: ``(join serial, path below it to the production)``: the order of one WME's joins
PATH: Final = 3
#: the other conditions of the production with the same alpha memory
TWINS: Final = 4
#: the condition's position in the kernel's order of the production's conditions
POSITION: Final = 5
#: the timetag when the production was loaded (its matches of older WMEs were made then)
LOADED: Final = 6
#: the path below the join cut at each positive join after it, with that join's written
#: index in between (the order of the matches one activation makes, depth first)
STEPS: Final = 7

# The fields of a tied new match's key (``_tied_keys``): its ``first`` (two fields), then
# ``kernel_key``'s after the newest WME.
_KEY_POSITION: Final = 2
_KEY_LINK: Final = 3
_KEY_PATH: Final = 4


def file_removals(agent: AgentState) -> None:
    """File the WMEs removed in the batch just taken with when the kernel's Rete took
    them out, as an ``_entry_rank``: after the batch's additions (``batch_sorted``),
    the last requested first (as watch 4 lists them); the batch is the latest that
    added a WME (this one, if it added any). Records of identifiers no
    longer in working memory are dropped when their number has doubled: no token can
    bind such an identifier again."""
    batch = len(agent._batch_starts)
    removed = agent._removed
    for wme in reversed(agent._removed_now):
        agent._removals += 1
        slots = removed.get(wme.id)
        if slots is None:
            slots = removed[wme.id] = {}
        key = vkey(wme.attr)
        bucket = slots.get(key)
        if bucket is None:
            bucket = slots[key] = {}
        bucket[wme] = (-batch, -agent._removals)
        agent._removed_size += 1
    agent._last_removed, agent._removed_now = agent._removed_now, []
    if agent._removed_size >= agent._removed_limit:
        for ident in [i for i in removed if i not in agent._refs and i not in agent._goals]:
            del removed[ident]
        agent._removed_size = sum(len(bucket) for slots in removed.values()
                                 for bucket in slots.values())
        agent._removed_limit = max(4096, 2 * agent._removed_size)


def _unblock_rank(agent: AgentState, cond: Condition, bindings: dict[str, Symbol]) -> tuple | None:
    """When the kernel's negative node of ``cond`` (a negated condition) last passed
    on a token of ``bindings``: the removal of the latest removed WME that matched it
    (the negation holds now, so that removal was of its last blocker), as an
    ``_entry_rank``; None when no such WME was removed (or its identifier is not
    bound: the token was then made by its positive WMEs)."""
    ident: Symbol | None = None
    for name in equality_vars(cond.id_test):
        ident = bindings.get(name)
        if ident is not None:
            break
    if ident is None:
        return None
    slots = agent._removed.get(ident)
    if slots is None:
        return None
    attr = cond.attr_test
    if type(attr) is Const:
        bucket = slots.get(vkey(attr.value))  # type: ignore[union-attr]
        buckets = [bucket] if bucket is not None else []
    else:
        buckets = list(slots.values())
    positive = Condition(cond.id_test, cond.attr_test, cond.value_test,
                         acceptable=cond.acceptable, goal=cond.goal)
    latest: tuple | None = None
    for bucket in buckets:
        for wme, rank in bucket.items():
            if (latest is None or rank < latest) and _wme_fits(positive, wme, bindings):
                latest = rank
    return latest


def _prefix_ranks(agent: AgentState, name: str, place: tuple, wmes: tuple) -> list[tuple | None]:
    """Per condition above the join of ``place`` in the kernel's order (its positive
    conditions ``place[BEFORE]`` and the negated conditions among them): when the kernel's
    Rete took the WME in (``_entry_rank``), or, for a negation, last passed its token
    on (``_unblock_rank``; None: never, or a conjunctive negation)."""
    starts = agent._batch_starts
    ordered = agent._kernel_order.ordered(name)
    if ordered is None or not any(kcond.negated for kcond in ordered[:place[POSITION]]):
        return [_entry_rank(wmes[j], starts) for j in place[BEFORE]]
    ranks: list[tuple | None] = []
    bindings: dict[str, Symbol] = {}
    seen: set[int] = set()
    for kcond in ordered[:place[POSITION]]:
        if kcond.is_ncc:
            ranks.append(None)
        elif kcond.negated:
            ranks.append(_unblock_rank(agent, kcond.element, bindings))
        elif kcond.index not in seen:
            seen.add(kcond.index)
            wme = wmes[kcond.index]
            ranks.append(_entry_rank(wme, starts))
            bindings = _wme_fits(kcond.element, wme, bindings) or bindings
    return ranks


def batch_sorted(agent: AgentState, new: list, start: int) -> list:
    """New matches in the order the kernel's Rete made them from one batch of WME
    changes (the WMEs newer than ``start``). The kernel adds a batch to its Rete newest
    first (measured: three ``(S1 ^x v)`` made by one firing each match one rule, whose
    firings come oldest WME first), so a match is made when its oldest WME of the batch
    enters, and the matches of older WMEs are made later; matches made by no new WME
    (a removal unblocked them) come last: the kernel removes a batch's WMEs after it
    has added them all (measured in soar_sml, the collapsed hanoi: the ^upper-disk
    that a move's removed ^above uncovers fires before the rejections that its new
    ^last-moved makes). See ``_kernel_key``."""
    creators = [_creator(match, start) for match in new]
    firsts: list[tuple] = []
    removed = agent._last_removed
    for k, creator in enumerate(creators):
        made: int = creator[0]
        if made <= start or (removed and _unblocked_now(new[k], removed)):
            firsts.append((2, made))
        else:
            firsts.append((1, -made))
    if len(new) == 2:  # the usual case, without sorting
        one: tuple
        two: tuple
        one, two = firsts
        if one == two:
            one, two = _tied_keys(agent, firsts, new, creators, None)
        return [new[1], new[0]] if two < one else new
    keys: list[tuple] = list(firsts)
    shared = _shared(firsts)
    if shared:
        keys = _tied_keys(agent, firsts, new, creators, shared)
    order = sorted(range(len(new)), key=keys.__getitem__)
    return [new[k] for k in order]


def _unblocked_now(match: object, removed: list[WME]) -> bool:
    """Whether a WME the batch removed matched a negated condition of ``match``: its
    token was blocked when its new WMEs entered, and the match was made when the
    removal unblocked it, after the batch's additions (measured in soar_sml, the
    farmer: never-undo, whose new operator enters while the ^failure it negates is
    still there, fires before the result*farmer matches of the same batch)."""
    production = match.production  # type: ignore[attr-defined]
    bindings = match.bindings  # type: ignore[attr-defined]
    for cond in production.conditions:
        if type(cond) is Condition and cond.negated:
            positive = Condition(cond.id_test, cond.attr_test, cond.value_test,
                                 acceptable=cond.acceptable, goal=cond.goal)
            for wme in removed:
                if _wme_fits(positive, wme, bindings) is not None:
                    return True
    return False


def _tied_keys(agent: AgentState, firsts: list[tuple], new: list, creators: list[tuple],
               shared: set[tuple] | None) -> list[tuple]:
    """``(first, *_kernel_key[1:])`` for each new match whose ``first`` another shares
    (in ``shared``; ``None``: all do), the others' ``first`` alone (it settles their
    order); the matches made at one join (same creating WME, alpha memory and path)
    also get the order of their tokens (``_token_order``) and one relinking time, the
    earliest: the kernel relinks a join once, when its parent memory gets its first
    token. Tokens are ordered only there: most ties are settled before, and ordering
    tokens is the dearest part of a key."""
    keys: list[tuple] = []
    joined: list[int] = []  # the keys that name a join
    for k in range(len(new)):
        first = firsts[k]
        if shared is not None and first not in shared:
            keys.append(first)
            continue
        key = first + _kernel_key(agent, new[k], creators[k])[1:]
        if len(key) > 4:
            joined.append(k)
        keys.append(key)
    if len(joined) < 2:
        return keys
    if len(joined) == 2:  # the usual tie: two joins, settled without the token order
        one, two = keys[joined[0]], keys[joined[1]]
        if (one[0] != two[0] or one[1] != two[1] or one[_KEY_POSITION] != two[_KEY_POSITION]
                or one[_KEY_PATH][0] != two[_KEY_PATH][0]):
            return keys
    joins: dict[tuple, list[int]] = {}
    for k in joined:
        key = keys[k]
        joins.setdefault((key[0], key[1], key[_KEY_POSITION], key[_KEY_PATH][0]),
                         []).append(k)
    for members in joins.values():
        if len(members) > 1:
            linked = min(keys[k][_KEY_LINK] for k in members)
            for k in members:
                full = _kernel_key(agent, new[k], creators[k], True)
                keys[k] = (*keys[k][:_KEY_LINK], linked, *full[_KEY_LINK:])
    return keys


def found_order(agent: AgentState, removed: list[Instantiation]) -> list[Instantiation]:
    """Fired matches that lost a WME, in the order the kernel's Rete finds them (to be
    retracted last found first): a removed WME's tokens are walked newest first (its
    ``w->tokens`` list), each with its subtree, so they retract in the order their
    tokens were made. Measured in soar_sml: when ``(S1 ^count 0)`` leaves, pop1 of
    ``(S1 ^thing T4)`` retracts before pop1 of the older ``(S1 ^thing T1)``: the count
    join made its tokens visiting the parent's newest first. A match was made when the
    last of its WMEs entered the Rete (``_creation_keys``), not by its newest WME."""
    keys = _creation_keys(agent, [inst.match for inst in removed])
    return [removed[k] for k in _latest_first(keys)]


def _creation_keys(agent: AgentState, matches: list) -> list:
    """Sort keys of the order the kernel's Rete made ``matches`` in: the batch of the
    newest WME, then the WME of that batch that entered last (a batch enters newest
    first: its oldest), then, only for ties, ``_kernel_key`` with the token order."""
    starts = agent._batch_starts
    creators: list[tuple] = []
    firsts: list[tuple] = []
    for match in matches:
        newest: int = match.newest[0]
        batch = _batch_of(starts, newest)
        made = _creator(match, starts[batch - 1] if batch else 0)
        creators.append(made)
        timetag: int = made[0]
        firsts.append((batch, -timetag))
    shared = _shared(firsts)
    if not shared:
        return firsts
    return _tied_keys(agent, firsts, matches, creators, shared)


def creation_key(agent: AgentState, match: object) -> tuple[int, int, int]:
    """Kernel order of match creation: by the newest matched WME; for one WME, by the
    alpha memory that passed it (the kernel visits ``(* ^attr *)`` before
    ``(* ^attr value)``), then the later-loaded production first."""
    newest, index = match.newest  # type: ignore[attr-defined]
    info = agent._productions.get(match.production.name)  # type: ignore[attr-defined]
    if info is None:
        return (newest, 0, 0)
    return (newest, info.cond_masks[index] if index >= 0 else 0, -info.load_index)


def kernel_sorted(agent: AgentState, items: list, matches: list,
                  newest_first: bool = False) -> list:
    """``items`` (stable) sorted by the ``_kernel_key`` of their ``matches``.  The key's
    first part, the newest WME, is all there is to compare when the matches' newest
    WMEs differ (the usual pair): the rest of the key is made only when needed."""
    if len(items) == 2:
        first, second = matches
        one, two = first.newest[0], second.newest[0]
        if one == two:
            one, two = _kernel_key(agent, first), _kernel_key(agent, second)
        if (one < two) if newest_first else (two < one):
            return [items[1], items[0]]
        return items
    keys = [match.newest[0] for match in matches]
    if len(set(keys)) < len(keys):
        keys = [_kernel_key(agent, match) for match in matches]
    order = sorted(range(len(items)), key=keys.__getitem__, reverse=newest_first)
    return [items[k] for k in order]


def _kernel_key(agent: AgentState, match: object, creator: tuple | None = None,
                tokens: bool = False) -> tuple:
    """The order the kernel's Rete makes new matches in: by the newest matched WME, then
    by the alpha memory it entered (``(* ^attr *)`` before ``(* ^attr value)``) and the
    path from the join it activated down to the production (``KernelOrder``).  A WME
    matched by several conditions makes the match in the last alpha memory it enters,
    at the first of them in the kernel's order. ``creator``: the WME that made the
    match and its index, when not the newest (see ``batch_sorted``); ``tokens``: order
    the matches one WME makes at one join too (``_token_order``)."""
    newest, index = creator or match.newest  # type: ignore[attr-defined]
    places = agent._kernel_places.get(match.production.name)  # type: ignore[attr-defined]
    if places is None:
        return (newest,)
    place = places.get(index)
    if place is None:
        return (newest,)
    if newest <= place[LOADED]:
        # Made when the production was loaded, in the order of loading (measured: of
        # two such rules with the same conditions, a new WME that blocks both retracts
        # the first loaded first, as it does the match made first at run time).
        return (newest, -1, -place[PATH][-1])
    wmes = match.wmes  # type: ignore[attr-defined]
    if place[TWINS]:  # the WME may be in other conditions too
        wme = wmes[index]
        for j in place[TWINS]:
            if wmes[j] is wme:
                other = places[j]
                if other[MASK] > place[MASK] or (other[MASK] == place[MASK]
                                                and other[POSITION] < place[POSITION]):
                    place = other
    # When its join was made, or relinked (see KernelOrder): the entry of the latest
    # WME before it, in the order the kernel's Rete took the WMEs in (the negated
    # _entry_rank). Joins relinked by one WME's entry go in the order it activated
    # them: its (* ^attr *) memory before (* ^attr value), each's joins by path.
    born: int = place[BORN]
    starts = agent._batch_starts
    link_batch = agent._born_batches.get(born)
    if link_batch is None:
        link_batch = agent._born_batches[born] = _batch_of(starts, born)
    own = tuple([wmes[j] for j in place[BEFORE]])
    linked = _token_link(place[BEFORE], own, places, born, link_batch, starts)
    if linked[1] != _LATEST:  # else linked since it was made (its memory never emptied)
        linked = _join_link(agent, match.production.name,  # type: ignore[attr-defined]
                            place, places, born, link_batch, own, linked)
    if not tokens:
        return (newest, place[MASK], linked, place[PATH])
    name: str = match.production.name  # type: ignore[attr-defined]
    return (newest, place[MASK], linked, (place[PATH][0],),
            *_token_order(wmes, place, agent._batch_starts,
                          _prefix_ranks(agent, name, place, wmes)))


def _join_link(agent: AgentState, name: str, place: tuple, places: dict[int, tuple], born: int,
               born_batch: int, own: tuple, own_link: tuple) -> tuple:
    """When the kernel's Rete last linked the join of ``place`` to its alpha memory
    (right unlinking: a join whose parent memory is empty is unlinked, and relinked
    when the memory gets a token), as a sort key (``_token_link`` of that token);
    ``own``: the match's token of that memory (its WMEs there), ``own_link`` its key.

    The memory's tokens are its prefix's partial matches in working memory; a record
    keeps the earliest of those seen while the memory is not emptied (``check_links``):
    a token seen there now was there since it was made. Only the matches' own tokens
    are seen, not all of the memory's when a record is made: that look-up is a search of
    working memory per new record, dearer than the rest of the key together, for a
    difference in very few programs' order. Measured in soar_sml, matching agent 8:
    op1x's ^stage join, linked by the first (X1 ^p 1) token, keeps its place before
    op0x's while the ^p WMEs are replaced one by one. A
    match whose token is gone (a retraction) was made in the link on record before
    this batch."""
    serial: int = place[PATH][0]
    record = agent._join_links.get(serial)
    if not _all_there(own, agent._wm):  # the token is gone now
        before = agent._links_before.get(serial)
        if before is not None:
            return before
        if record is not None and record.looked != agent._collects:
            return record.link
        return own_link
    if record is not None:
        seen = record.seen
        if own not in seen:
            seen.add(own)
            _live_tokens(seen, agent._wm)
            if own_link < record.link:  # there now, so the memory was not empty since
                record.link = own_link
                return own_link
        return record.link
    starts = agent._batch_starts
    if own_link[0] == len(starts) and starts:  # made now, and no link on record
        older = _older_token(agent, name, place, starts[-1])
        if older is not None:
            own, own_link = older, _token_link(place[BEFORE], older, places, born,
                                               born_batch, starts)
    agent._join_links[serial] = JoinLink(own_link, own, name, place, agent._collects, {own})
    return own_link


def _older_token(agent: AgentState, name: str, place: tuple, start: int) -> tuple | None:
    """A token of the kernel's memory above the join of ``place`` made before this
    batch (of WMEs no newer than ``start``, those the batch removed included: the
    kernel takes them out after the batch's additions), or None. A join whose link
    was never asked for has no record (``_join_link``): its memory did not empty when
    a new token came in if such a token was there (measured in soar_sml, the farmer
    crossing with the wolf: the new (F1 ^on R4) replaces (F1 ^on L2) in the tokens of
    the passenger's ^on join, which keeps its place before result*stays's join)."""
    ordered = agent._kernel_order.ordered(name)
    if ordered is None:
        return None
    removed = agent._last_removed

    def candidates(cond: Condition, bindings: dict[str, Symbol]) -> list[WME]:
        found = [wme for wme in agent._candidates(cond, bindings) if wme.timetag <= start]
        return found + removed if removed else found

    return prefix_token(ordered, place[POSITION], candidates, place[BEFORE])


def _memory_token(agent: AgentState, name: str, place: tuple) -> tuple | None:
    """A token of the kernel's memory above the join of ``place`` (see
    ``_join_link``), as the WMEs of the conditions ``place[BEFORE]``; None if it is empty."""
    ordered = agent._kernel_order.ordered(name)
    if ordered is None:
        return None
    return prefix_token(ordered, place[POSITION], agent._candidates, place[BEFORE])


def check_links(agent: AgentState) -> None:
    """After a batch of WME changes: a recorded join (``_join_link``) whose token on
    record lost a WME stays linked, with another token on record (one seen before, or
    else one looked up in working memory), if its memory still has one (the kernel
    adds a batch's WMEs before it removes any, so a token that replaces another keeps
    the memory from emptying), and is forgotten if not. The links of the batch before
    are kept for ordering retractions."""
    wm = agent._wm
    if agent._links_before:
        agent._links_before = {}
    gone = [serial for serial, record in agent._join_links.items()
            if not _all_there(record.witness, wm)]
    for serial in gone:
        record = agent._join_links[serial]
        agent._links_before[serial] = record.link
        seen = {token for token in record.seen if _all_there(token, wm)}
        if seen:
            witness = next(iter(seen))
        else:
            found = _memory_token(agent, record.production, record.place)
            if found is None:
                del agent._join_links[serial]
                continue
            witness = found
            seen.add(witness)
        record.witness, record.seen = witness, seen


_LATEST = float("inf")  # a join made between two batches: after every WME of the first


def _latest_first(keys: list) -> list[int]:
    """``sorted(range(len(keys)), key=keys.__getitem__, reverse=True)``; the few keys of
    the usual retraction (three in hanoi) by insertion, without sorted's calls."""
    if len(keys) > 8:
        return sorted(range(len(keys)), key=keys.__getitem__, reverse=True)
    order: list[int] = []
    for k in range(len(keys)):
        key = keys[k]
        place = len(order)
        while place > 0 and keys[order[place - 1]] < key:  # after the equal ones: stable
            place -= 1
        order.insert(place, k)
    return order


def _entry_rank(wme: WME, starts: list[int]) -> tuple[int, int]:
    """When the kernel's Rete took ``wme`` in, as a sort key, latest first: batch after
    batch (``starts``: the timetag before each), a batch's WMEs newest first."""
    timetag: int = wme.timetag
    return (-_batch_of(starts, timetag), timetag)


def _batch_of(starts: list[int], timetag: int) -> int:
    """``bisect_left(starts, timetag)``: the batch of a WME (see ``_entry_rank``), in
    native integers (the bisect module compares Python objects), and searched from both
    ends at once, doubling the steps, where the batches of the WMEs asked about mostly
    are: the newest, and the structure made when the run began (a search from the end
    alone would take longer the longer the run)."""
    high = len(starts) - 1
    if high < 0 or starts[high] < timetag:
        return high + 1
    if starts[0] >= timetag:
        return 0
    low = 0  # from here on starts[low] < timetag <= starts[high]
    step = 1
    while high - low > 1:
        probe = high - step
        if probe <= low:
            break
        if starts[probe] < timetag:
            low = probe
            break
        high = probe
        probe = low + step
        if probe >= high:
            break
        if starts[probe] >= timetag:
            high = probe
            break
        low = probe
        step <<= 1
    while high - low > 1:
        middle = (low + high) >> 1
        if starts[middle] < timetag:
            low = middle
        else:
            high = middle
    return high


def _creator(match: object, start: int) -> tuple:
    """The timetag and first index of the match's oldest WME newer than ``start`` (its
    newest WME when none is). (The kernel-order keys are plain tuples: mypyc would unpack
    a ``tuple[int, int]`` into a C struct and box it anew at every use.)"""
    found: tuple = match.newest  # type: ignore[attr-defined]
    newest: int = found[0]
    if newest <= start:
        return found
    oldest, index = newest, -1
    wmes: tuple[WME | None, ...] = match.wmes  # type: ignore[attr-defined]
    for i, wme in enumerate(wmes):
        if wme is not None:
            timetag: int = wme.timetag
            if start < timetag < oldest:
                oldest, index = timetag, i
    return found if index < 0 else (oldest, index)


def _token_link(order: tuple[int, ...], token: tuple, places: dict[int, tuple], born: int,
                born_batch: int, starts: list[int]) -> tuple:
    """The time a token (the WMEs of the written conditions ``order``) was made, as the
    relinking key of the join below its memory: the entry of its latest WME newer than
    the join, in the order the kernel's Rete took them (batch after batch, a batch newest
    first), with that WME's alpha memory and path (joins relinked by one WME go in the
    order it activated them); ``(born_batch, _LATEST)`` when none is newer than the join."""
    link_batch, link_time = born_batch, 0
    link_place: tuple | None = None
    for j, wme in zip(order, token, strict=True):
        if wme is None:
            continue
        timetag: int = wme.timetag
        if timetag > born:
            batch = _batch_of(starts, timetag)
            if batch > link_batch or (link_place is not None and batch == link_batch
                                      and -timetag > link_time):
                link_batch, link_time, link_place = batch, -timetag, places.get(j)
    if link_place is None:
        return (link_batch, _LATEST)
    return (link_batch, link_time, link_place[MASK], link_place[PATH])


def _live_tokens(seen: set[tuple], wm: dict[int, WME]) -> None:
    """Drop from a link record's ``seen`` the tokens that lost a WME (they never come
    back: a WME that leaves is never added again), when their number has doubled since
    the last time: a record whose token on record stays keeps seeing new tokens, one or
    two a decision, and would otherwise keep every one of them for the rest of the run."""
    size = len(seen)
    if size >= 16 and not size & (size - 1):  # a power of two
        for token in [token for token in seen if not _all_there(token, wm)]:
            seen.discard(token)


def _all_there(wmes: tuple, wm: dict[int, WME]) -> bool:
    """Whether every WME of a token (``None``: a condition it has no WME for) is still in
    working memory (by timetag)."""
    for wme in wmes:
        if wme is not None and wm.get(wme.timetag) is not wme:
            return False
    return True


def _shared(firsts: list[tuple]) -> set[tuple]:
    """The keys that occur more than once (none, usually)."""
    if len(firsts) == 2:
        return {firsts[0]} if firsts[0] == firsts[1] else set()
    seen: set[tuple] = set()
    shared: set[tuple] = set()
    for first in firsts:
        if first in seen:
            shared.add(first)
        seen.add(first)
    return shared


def _token_creation_key(ranks: list[tuple | None], sign: int) -> tuple:
    """The order the kernel's Rete made tokens in, from the ``_entry_rank``s of their
    WMEs in its condition order (``sign`` 1: made first first; -1: the reverse), and of
    the last unblocking of its negations (``_prefix_ranks``; None: not known). A
    token was made when its latest WME entered or its latest negation unblocked it: by a
    right activation that visited the parent's tokens latest made first (or a negative
    node passing the one token on), then by left activations down to here, each visiting
    its alpha memory's WMEs latest entered first (a negative node, passed through, adds
    nothing to the order: measured in soar_sml, n-queens with indifferent-selection
    --first: the squares of a column unblocked at decisions 7, 10 and 11 are proposed
    again in that order, after the backtrack at decision 12)."""
    known = [k for k in range(len(ranks)) if ranks[k] is not None]
    if not known:
        return ()
    k = min(known, key=ranks.__getitem__)  # the latest entered
    latest: tuple = ranks[k]  # type: ignore[assignment]
    after = [r for r in ranks[k + 1:] if r is not None]
    return (
        (-sign * latest[0], -sign * latest[1]),
        *_token_creation_key(ranks[:k], -sign),
        *[(sign * r[0], sign * r[1]) for r in after],
    )


def _token_order(wmes: tuple, place: tuple, starts: list[int], before: list[tuple | None]) -> tuple:
    """The order in which one WME's activation of a join makes several matches, as the
    kernel's Rete does (measured in soar_sml: two ``^thing`` WMEs of one firing, then a
    ``^count`` joined after them, fire the proposal of the older ``^thing`` first; items
    whose tokens one ``^box`` WME made fire in the order its ``^item`` WMEs entered). Its
    memories list items newest first: a right activation visits the parent's tokens latest
    made first, a left activation the alpha memory's WMEs latest entered first; and each
    token goes down to every child (newest first) before the next is made, so the key
    alternates the path to the next join and the rank of that join's WME (depth first:
    measured in soar_sml, (S1 ^go n) below the shared ^obj join makes pb of X2, pa of X2,
    then pb of X1)."""
    order: list[tuple] = [_token_creation_key(before, -1)]
    steps: tuple = place[STEPS]
    for k in range(len(steps)):
        step = steps[k]
        if k & 1:  # a join below: its alpha memory's WMEs are visited latest entered first
            wme = wmes[step]
            order.append(_entry_rank(wme, starts) if wme is not None else (0, 0))
        else:  # the path to the next join (children newest first)
            order.append(step)
    return tuple(order)
