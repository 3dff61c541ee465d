"""Top-level commands of agent files."""

from __future__ import annotations

import io

import pytest

from sann.soar import Agent, SoarError, SoarRuntimeError


def agent_with(text: str) -> tuple[Agent, io.StringIO]:
    out = io.StringIO()
    agent = Agent(out=out)
    agent.load(text)
    return agent, out


def test_watch_trace_levels() -> None:
    agent, _ = agent_with("watch 3")
    assert agent.trace_level == 3
    agent.load("trace --level 1")
    assert agent.trace_level == 1
    agent.load("watch 0")
    assert agent.trace_level == 0
    with pytest.raises(SoarRuntimeError, match="trace level"):
        agent.load("watch 7")


def test_settings_commands() -> None:
    agent, out = agent_with(
        "srand 42\nmax-elaborations 7\nmulti-attributes foo 3\n"
        "indifferent-selection --epsilon-greedy\nindifferent-selection --epsilon 0.2\n"
        "decide indifferent-selection --first\nnumeric-indifferent-mode --avg\n"
        "learn --off\nchunk never\noutput console on\necho hello world\n"
    )
    assert agent.max_elaborations == 7
    assert agent.multi_attributes == {"foo": 3}
    assert agent.exploration.policy == "first"
    assert agent.exploration.epsilon == 0.2
    assert agent.exploration.numeric_mode == "avg"
    assert out.getvalue() == "hello world\n"


def test_srand_makes_random_choices_reproducible() -> None:
    rules = (
        "indifferent-selection --random\n"
        "sp {p (state <s> ^superstate nil) --> (<s> ^operator <a> + = ^operator <b> + ="
        " ^operator <c> + =) (<a> ^name a) (<b> ^name b) (<c> ^name c)}\n"
        "sp {q (state <s> ^operator <o>) --> (<s> ^operator <o> -)}\n"
    )
    runs = []
    for _ in range(2):
        agent, _ = agent_with("srand 5\n" + rules)
        agent.run(6)
        runs.append(agent.operator_sequence)
    assert runs[0] == runs[1]


_LEARNS = (
    "sp {go (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)}\n"
    "sp {done (state <s> ^operator <o>) (<o> ^name go ^answer <a>) --> (<s> ^done <a>)}\n"
    "sp {init (state <s> ^superstate nil) --> (<s> ^x 3)}\n"
    "sp {sub (state <s> ^impasse no-change ^superstate <ss>) (<ss> ^x <x> ^operator <o>)"
    " --> (<o> ^answer <x>)}\n"
)


@pytest.mark.parametrize("text", ["learn --on", "chunk always", "learn -e"])
def test_learning_on_learns_a_chunk(text: str) -> None:
    agent, out = agent_with(text + "\n" + _LEARNS)
    assert agent.learning == "always"
    agent.run(3)
    chunks = [name for name, info in agent._productions.items()
              if "chunk" in info.production.flags]
    assert chunks == ["chunk*sub*t2-1"]  # the kernel's name for it (soar_sml 9.6)
    out.seek(0)
    out.truncate()
    agent.load("print --chunks\nexplain chunk*sub*t2-1")
    assert out.getvalue().startswith("chunk*sub*t2-1 \n")
    assert "1: sub\n" in out.getvalue()
    agent.load("init-soar")
    assert "chunk*sub*t2-1" in agent._productions  # init-soar keeps chunks
    agent.load("excise --chunks")
    assert "chunk*sub*t2-1" not in agent._productions and "sub" in agent._productions


@pytest.mark.parametrize("text", ["excise-everything now", "rl --set learning on", "gp {}"])
def test_unknown_commands_name_themselves(text: str) -> None:
    with pytest.raises(SoarRuntimeError) as info:
        agent_with(text)
    assert text.split()[0] in str(info.value)


def test_bad_arguments() -> None:
    for text in (
        "max-elaborations 0",
        "max-elaborations x",
        "srand a",
        "popd",
        "indifferent-selection --epsilon 3",
        "pushd /no/such/dir",
    ):
        with pytest.raises(SoarRuntimeError):
            agent_with(text)


def test_pushd_popd_and_source(tmp_path) -> None:
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "r.soar").write_text("sp {r (state <s> ^superstate nil) --> (<s> ^r 1)}\n")
    (tmp_path / "main.soar").write_text("pushd lib\nsource r.soar\npopd\n")
    agent = Agent(out=io.StringIO())
    agent.source(tmp_path / "main.soar")
    assert agent.productions == ["r"]


def test_excise_and_init_soar_commands() -> None:
    agent, _ = agent_with("sp {r (state <s> ^superstate nil) --> (<s> ^r 1)}\nexcise r\n")
    assert agent.productions == []
    agent.load("init-soar")
    assert agent.stats["wm_size"] == 13


# Forms the kernel (soar_sml 9.6) accepts that leave this engine's behaviour unchanged.
@pytest.mark.parametrize(
    "text",
    [
        "rl --set learning off", "rl -s learning off", "rl -s learning-rate 0.1", "rl",
        "epmem --set learning off", "smem --disable", "smem -d", "smem --set learning off",
        "timers --off", "timers --on", "timers -d", "soar timers on", "soar timers off",
        "watch --learning print", "trace --learning fullprint", "excise --chunks",
        "excise -c", "soar stop-phase apply", "soar", "alias", "max-gp 5", "soar max-gp 9",
        "svs --disable", "svs -d", "wma --set activation off", "wma -s activation off",
        "max-nil-output-cycles 20", "soar max-nil-output-cycles 20", "soar tcl off",
    ],
)  # fmt: skip
def test_accepted_no_op_forms(text: str) -> None:
    agent, out = agent_with(text)
    assert out.getvalue() == ""
    assert agent.trace_level == 0


@pytest.mark.parametrize(
    ("text", "feature"),
    [
        ("rl --set learning on", "reinforcement learning"), ("rl -s learning on", "RL"),
        ("epmem --set learning on", "episodic memory"), ("smem --enable", "semantic memory"),
        ("smem -e", "semantic memory"), ("smem --set learning on", "semantic memory"),
        ("smem --add {(<x> ^a b)}", "smem"), ("soar stop-phase output", "apply phase"),
        ("run -e 3", "run"), ("soar version", "sub-command"), ("timers maybe", "on or off"),
        ("svs --enable", "Spatial Visual System"), ("wma -s activation on", "activation"),
        ("max-nil-output-cycles 0", "positive integer"), ("soar tcl on", "Tcl"),
        ("production find r", "production excise"),
    ],
)  # fmt: skip
def test_forms_needing_missing_features_are_refused_clearly(text: str, feature: str) -> None:
    with pytest.raises(SoarRuntimeError, match=feature):
        agent_with(text)


def test_production_excise_is_excise() -> None:
    agent, _ = agent_with("sp {r (state <s> ^superstate nil) --> (<s> ^r 1)}\n"
                          "sp {q (state <s> ^superstate nil) --> (<s> ^q 1)}\n"
                          "production excise r\n")
    assert agent.productions == ["q"]
    agent.load("production excise --all")
    assert agent.productions == []


def test_settings_through_soar_and_aliases() -> None:
    agent, out = agent_with(
        "soar max-elaborations 7\nwarnings --off\nmax-goal-depth 9\n"
        "alias me soar max-elaborations\nme 8\nalias -r me\n"
    )
    assert agent.max_elaborations == 8
    assert agent.warnings is False and agent.max_goal_depth == 9
    agent.load("warnings --on\nwarnings")
    assert agent.warnings is True
    assert out.getvalue() == "warnings is on\n"
    with pytest.raises(SoarRuntimeError, match="unknown or unsupported command: me"):
        agent.load("me 5")


def test_wait_snc_sets_the_agent_flag() -> None:
    agent, out = agent_with("waitsnc --on")
    assert agent.wait_snc is True
    agent.load("soar wait-snc off\nwaitsnc")
    assert agent.wait_snc is False
    assert out.getvalue() == "wait-snc is off\n"
    agent.load("soar wait-snc on\nwaitsnc -d\nwaitsnc -e")
    assert agent.wait_snc is True


COUNTER = (
    "sp {propose (state <s> ^superstate nil -^n) --> (<s> ^operator <o> +) (<o> ^name go)}\n"
    "sp {apply (state <s> ^operator.name go) --> (<s> ^n 1) (write |applied|)}\n"
)


def test_init_and_soar_init_reinitialise() -> None:
    agent, _ = agent_with(COUNTER + "run 1\n")
    assert agent.stats["decisions"] == 1
    agent.load("init")
    assert agent.stats["decisions"] == 0 and agent.stats["wm_size"] == 13
    agent.run(2)
    agent.load("soar init")
    assert agent.stats["decisions"] == 0 and agent.productions == ["propose", "apply"]


def test_run_in_a_file_runs_as_the_kernel_does() -> None:
    # The kernel runs `run N` at source time: `source` of this text makes 3 decisions.
    agent, out = agent_with(COUNTER + "run 3\n")
    assert agent.stats["decisions"] == 3
    assert out.getvalue() == "applied"
    agent.load("run -d 2")
    assert agent.stats["decisions"] == 5


def test_print_and_stats_at_source_time() -> None:
    agent, out = agent_with(COUNTER + "print --all\nprint apply\nprint -d 1 s1\nstats\n")
    text = out.getvalue()
    assert text.startswith("apply \npropose \nsp {apply\n")
    assert "(S1 ^epmem E1 ^io I1 ^reward-link R1" in text and "^superstate nil" in text
    assert "0 decisions\n" in text and "WM size: 13 current" in text


def test_excise_groups() -> None:
    rules = (
        "sp {user (state <s> ^superstate nil) --> (<s> ^a 1)}\n"
        "sp {lib :default (state <s> ^superstate nil) --> (<s> ^b 1)}\n"
    )
    agent, _ = agent_with(rules + "excise --user")
    assert agent.productions == ["lib"]
    agent, _ = agent_with(rules + "excise -d")
    assert agent.productions == ["user"]
    agent, _ = agent_with(rules + "excise --chunks\nexcise -a")
    assert agent.productions == []
    with pytest.raises(SoarRuntimeError, match="unknown option"):
        agent_with("excise --bogus")


def test_gp_generates_every_combination_with_the_kernels_names() -> None:
    agent, out = agent_with(
        "gp {gen (state <s> ^foo [a b c] ^baz [1 2]) --> (<s> ^bar [x |y z|])}\n"
        "print gen*1\nprint gen*11\n"
    )
    # The kernel numbers the combinations with the first list varying fastest.
    assert agent.productions == [f"gen*{n}" for n in range(1, 13)]
    assert out.getvalue() == (
        "sp {gen*1\n    (state <s> ^foo a ^baz 1)\n    -->\n    (<s> ^bar x)\n}\n"
        "sp {gen*11\n    (state <s> ^foo b ^baz 2)\n    -->\n    (<s> ^bar |y z|)\n}\n"
    )
    agent, _ = agent_with("gp {one (state <s> ^[a b] 1 ^c |[x]|) --> (<s> ^d 1)} # [no]\n")
    assert agent.productions == ["one*1", "one*2"]
    agent, _ = agent_with("gp {single (state <s> ^foo a) --> (<s> ^bar b)}")
    assert agent.productions == ["single*1"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("gp {e (state <s> ^foo []) --> (<s> ^b 1)}", "empty value collections"),
        ("gp {e (state <s> ^foo [a b) --> (<s> ^b 1)}", "unmatched values bracket"),
        ("gp {e (state <s> ^foo a]) --> (<s> ^b 1)}", "without"),
        ("gp {e (state <s> ^foo [a [b]]) --> (<s> ^b 1)}", "nested"),
        ("max-gp 3\ngp {e (state <s> ^f [a b] ^g [c d]) --> (<s> ^b 1)}", "gp-max of 3"),
    ],
)
def test_gp_errors_say_where(text: str, message: str) -> None:
    with pytest.raises(SoarRuntimeError, match=message) as info:
        agent_with("\n" + text)
    assert "<string>:2" in str(info.value) or "<string>:3" in str(info.value)


def test_gp_syntax_error_points_into_the_file() -> None:
    with pytest.raises(SoarError) as info:
        agent_with("\n\ngp {bad (state <s> ^foo [a b] --> (<s> ^bar 1)}")
    assert ":3:" in str(info.value) and "bad*1" in str(info.value)


_FLAGGED = (
    "sp {go (state <s> ^superstate nil -^done) --> (<s> ^operator <o> +) (<o> ^name go)}\n"
    "sp {done (state <s> ^operator <o>) (<o> ^name go ^answer <a>) --> (<s> ^done <a>)}\n"
    "sp {init (state <s> ^superstate nil) --> (<s> ^x 3)}\n"
    "sp {mark (state <s> ^impasse no-change) --> (FLAG <s>) (<s> ^ready yes)}\n"
    "sp {sub (state <s> ^impasse no-change ^ready yes ^superstate <ss>)"
    " (<ss> ^x <x> ^operator <o>) --> (<o> ^answer <x>)}\n"
)


@pytest.mark.parametrize(("mode", "flag", "learns"), [
    ("only", "force-learn", True), ("only", "dont-learn", False),
    ("except", "dont-learn", False), ("except", "force-learn", True),
    ("always", "dont-learn", True),
])  # each as soar_sml 9.6 does
def test_chunk_only_and_except_follow_force_and_dont_learn(mode: str, flag: str,
                                                          learns: bool) -> None:
    agent, _ = agent_with(f"chunk {mode}\n" + _FLAGGED.replace("FLAG", flag))
    agent.run(3)
    learned = [name for name, info in agent._productions.items()
               if "chunk" in info.production.flags]
    assert learned == (["chunk*sub*t2-1"] if learns else [])
