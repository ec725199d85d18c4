"""The agent registry: its errors list what exists, and bad parameters are named."""

import pytest

import agents
from mimo_radar_env import load_scenario

PAPER = load_scenario("paper-3")  # K = 2, Omega = [0.6, 0.4]


def test_registry_errors_list_what_exists():
    with pytest.raises(ValueError, match="unknown agent 'ucb2'; available agents are .*mg-crb-cl"):
        agents.make_agent("ucb2", PAPER)
    # an unknown or missing keyword is a TypeError, as Python raises for a class's keywords (and
    # Gymnasium for gym.make's), and the ValueError of the library's other bad input
    with pytest.raises(
        TypeError, match=r"unknown parameter\(s\) \['gamma'\] for agent 'ucb1'; allowed: .*beta"
    ) as unknown:
        agents.make_agent("ucb1", PAPER, gamma=3)
    assert isinstance(unknown.value, ValueError)
    with pytest.raises(TypeError, match=r"agent 'ppo' needs the parameter\(s\) \['path'\]"):
        agents.make_agent("ppo", PAPER)
    assert {
        "mg-crb-cl",
        "ucb1",
        "epsilon-greedy",
        "fix1",
        "fix2",
        "best",
        "discounted-ucb",
        "sliding-window-ucb",
        "discounted-thompson",
        "cucb",
        "random",
    } <= set(agents.available_agents())


@pytest.mark.parametrize(
    ("name", "message"),
    [
        (None, "got NoneType None"),
        (3, "got int 3"),
        (
            agents.agent_class("ucb1"),
            r"got the class UCB1 \(make it by calling it: UCB1\(scenario, seed=...\)\)",
        ),
    ],
)
def test_an_agent_named_by_anything_but_a_str_is_a_type_error_saying_what_was_given(name, message):
    """make_agent, agent_parameters and split_policy take a name: anything else is one TypeError
    naming it (None read ``.partition`` of it, an AttributeError), a class with how to make it."""
    for call in (
        lambda: agents.make_agent(name, PAPER),
        lambda: agents.agent_parameters(name),
        lambda: agents.split_policy(name),
    ):
        with pytest.raises(
            TypeError, match=r"an agent's name must be a str, a registered name or module:Class, "
        ):
            call()
        with pytest.raises(TypeError, match=message):
            call()


@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        ("mg-crb-cl", {"alpha": 1.5}, r"alpha must be in \[0, 1\], got 1.5"),
        ("mg-crb-cl", {"beta": -1}, r"beta must be in \[0, inf\), got -1"),
        ("discounted-ucb", {"discount": 0.0}, r"discount must be in \(0, 1\], got 0.0"),
        ("discounted-thompson", {"prior_rate": 0}, r"prior_rate must be in \(0, inf\), got 0"),
        ("sliding-window-ucb", {"window": 0}, r"window must be in \[1, 1,000,000\], got 0"),
        ("sliding-window-ucb", {"window": 5.0}, r"window must be an integer in \[1, 1,000,000\], got 5.0"),
        ("epsilon-greedy", {"epsilon": 2}, r"epsilon must be in \[0, 1\], got 2"),
    ],
)
def test_bad_agent_parameters_are_named(name, params, message):
    with pytest.raises(ValueError, match=message):
        agents.make_agent(name, PAPER, **params)


def test_register_agent_refuses_what_is_no_agent_class_and_keeps_the_shipped_names():
    """It took any object (make_agent then failed, or called it) and replaced a shipped agent for
    the whole process: ``register_agent("ucb1", Mine)`` would have benchmarked Mine as UCB1. A
    name of one's own may be registered again, the last class winning (a notebook cell run twice)."""
    from agents.registry import _REGISTRY, _SHIPPED
    from agents.ucb import UCB1

    for cls in (3, dict, UCB1(load_scenario("paper-1-v1"))):
        with pytest.raises(TypeError, match=r"cls must be a subclass of agents\.Agent, got "):
            agents.register_agent("mine", cls)
    for name in ("", " ", "a,b", 3):
        with pytest.raises(ValueError, match="name must be a non-empty string without commas"):
            agents.register_agent(name, UCB1)
    assert {"mg-crb-cl", "ucb1", "epsilon-greedy", "fix1", "fix2", "best"} <= _SHIPPED
    for shipped in sorted(_SHIPPED):
        with pytest.raises(ValueError, match=f"'{shipped}' is a shipped agent and keeps its meaning"):
            agents.register_agent(shipped, UCB1)
    assert isinstance(agents.make_agent("ucb1", "paper-1-v1"), UCB1)
    assert "mine" not in agents.available_agents()

    class Mine(UCB1):
        pass

    class Again(UCB1):
        pass

    try:
        agents.register_agent("mine", Mine)
        agents.register_agent("mine", Again)
        assert type(agents.make_agent("mine", "paper-1-v1")) is Again
    finally:
        _REGISTRY.pop("mine", None)


@pytest.mark.parametrize("name", ["fix1", "plan-tracking-mcts", "ucb1"])
def test_a_made_agent_is_named_as_it_was_made_in_its_messages(name):
    """A preset of a shared class (fix1 of the fixed agent, plan-tracking-mcts of plan-tracking)
    names itself as made: its errors said "fixed"."""
    agent = agents.make_agent(name, PAPER, seed=0)
    assert agent.name == name
    obs = agents.Rollout(agent, agents.make_env(agent, 3), seed=0).obs  # reset, the oracle attached
    with pytest.raises(ValueError, match=rf"^{name} was reset on 3 trial\(s\), and this observation holds 2"):
        agent.act({key: value[:2] for key, value in obs.items()})
