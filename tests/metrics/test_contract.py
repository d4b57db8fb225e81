"""The bag contract as code: ``EpisodeFacts`` survives its encoders and the decoder. That the
bridge's recorder writes the facts as the synthetic bags do is
tests/bridge/test_recorder_contract.py's."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

from contract_helpers import ENV_FACTS
from hypothesis import given, settings
from hypothesis import strategies as st

from pic4rl_base.geometry import Footprint, Pose2D
from pic4rl_base.goal import Goal
from pic4rl_metrics import contract
from pic4rl_metrics.contract import FACT_KEYS, EpisodeFacts, Outcome, parse_facts

FINITE = st.floats(allow_nan=False, allow_infinity=False, width=64)
POSITIVE = st.floats(min_value=1e-6, max_value=1e6, allow_nan=False)
NON_NEGATIVE = st.floats(min_value=0.0, max_value=1e6, allow_nan=False)
TEXT = st.text(st.characters(codec="utf-8", exclude_categories=("Cs",)), min_size=1, max_size=12)
POINT = st.tuples(FINITE, FINITE)


def _optional(strategy: st.SearchStrategy) -> st.SearchStrategy:
    return st.one_of(st.none(), strategy)


FOOTPRINTS = st.one_of(
    st.builds(Footprint, radius_m=POSITIVE),
    st.builds(Footprint, length_m=POSITIVE, width_m=POSITIVE),
)
FACTS = st.builds(
    EpisodeFacts,
    agent=_optional(TEXT), task=_optional(TEXT), world=_optional(TEXT), robot=_optional(TEXT),
    run=_optional(TEXT), episode=_optional(TEXT),
    seed=_optional(st.integers(-(2**63), 2**63 - 1)),
    footprint=_optional(FOOTPRINTS),
    start=_optional(st.tuples(FINITE, FINITE, FINITE)),
    goal=_optional(st.one_of(POINT, st.builds(Goal, FINITE, FINITE, FINITE))),
    goal_tolerance_m=_optional(NON_NEGATIVE),
    collision_tolerance_m=_optional(NON_NEGATIVE),
    safety_margin_m=_optional(NON_NEGATIVE),
    max_speed_mps=_optional(POSITIVE),
    row_centerline=_optional(st.lists(POINT, min_size=2, max_size=5).map(tuple)),
    shortest_path_m=_optional(st.one_of(POSITIVE, st.just(math.inf))),
    straight_line_m=_optional(POSITIVE),
    reference_path_m=_optional(POSITIVE),
    scan_mount=_optional(st.builds(Pose2D, FINITE, FINITE, FINITE)),
    outcome=_optional(st.sampled_from(list(Outcome))),
    extra=st.dictionaries(TEXT.filter(lambda k: k not in FACT_KEYS), TEXT, max_size=3),
)



@settings(max_examples=200, deadline=None)
@given(FACTS)
def test_facts_round_trip_through_custom_data(facts: EpisodeFacts) -> None:
    custom = facts.custom_data()
    assert all(isinstance(v, str) for v in custom.values())
    decoded, given_ = parse_facts(custom, source="custom_data")
    assert decoded == facts
    assert given_ == frozenset(custom) - set(facts.extra) | ({"extra"} if facts.extra else set())


@settings(max_examples=200, deadline=None)
@given(FACTS)
def test_facts_round_trip_through_the_facts_topic_json(facts: EpisodeFacts) -> None:
    decoded, _ = parse_facts(json.loads(facts.facts_json()), source="facts topic")
    assert decoded == facts


def test_custom_data_keeps_the_contract_order_and_format() -> None:
    custom = ENV_FACTS.custom_data()
    assert list(custom) == [k for k in FACT_KEYS if k in custom]
    assert custom["seed"] == "7" and custom["start"] == "[0.0, 0.0, 0.0]"
    assert custom["footprint"] == '{"length_m": 0.508, "width_m": 0.43}'
    assert custom["scan_mount"] == '{"x_m": 0.12, "y_m": 0.0, "yaw_rad": 0.0}'
    assert custom["shortest_path_m"] == "inf" and custom["safety_margin_m"] == "0.1"
    assert "outcome" not in custom and "row_centerline" not in custom


def test_the_fact_keys_are_the_facts_fields_and_each_has_a_doc_row() -> None:
    """A new fact is one field: FACT_KEYS follow it, and docs/interfaces.md's table names it."""
    names = [f.name for f in dataclasses.fields(EpisodeFacts)]
    assert list(FACT_KEYS) == [n for n in names if n not in ("outcome_stamp_ns", "extra")]
    doc = (Path(__file__).resolve().parents[2] / "docs" / "interfaces.md").read_text()
    table = doc.split("| fact key | value |", 1)[1].split("\n\n", 1)[0]
    documented = {key for line in table.splitlines()[2:]
                  for key in re.findall(r"`(\w+)`", line.split("|")[1])}
    assert documented == set(FACT_KEYS)


def test_unknown_tolerances_are_not_written_and_read_as_the_defaults() -> None:
    facts = EpisodeFacts(agent="a")
    assert facts.custom_data() == {"agent": "a"}
    assert facts.with_defaults().goal_tolerance_m == 0.4  # the env's default
    assert facts.with_defaults().collision_tolerance_m == 0.05
    assert facts.with_defaults().safety_margin_m == 0.3


def test_the_outcome_event_reads_back() -> None:
    assert contract.parse_outcome_event(contract.outcome_event(Outcome.GOAL, 12)) == (
        Outcome.GOAL, 12)
    assert contract.parse_outcome_event("timeout") == (Outcome.TIMEOUT, None)
