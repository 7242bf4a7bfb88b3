"""The measured twin/full-robot status confusion (issue 37, part 4): the shipped data,
its smoothing, and the real belief update that weighs real keys by it."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from planners.errors import ConfigError, UnknownNameError
from strug_manip.domains.manipulation import twin_keys
from strug_manip.domains.manipulation.actions import ManipAction
from strug_manip.domains.manipulation.model import MISMATCH, ManipulationPOMDP, key_loglik
from strug_manip.domains.manipulation.state import ManipState, observation_key

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))

import measure_twin_confusion  # noqa: E402


def _state(status: str, holding: bool = False) -> ManipState:
    """A particle state whose twin's last key had ``status`` (the handle unmoved)."""
    return ManipState(0, None, 1, observation_key(status, holding, np.zeros(3)))  # type: ignore[arg-type]


def _confusion(pairs: list[tuple[str, str]]) -> twin_keys.TwinConfusion:
    return twin_keys.TwinConfusion(
        twin_keys.STATUSES, twin_keys.count_pairs(pairs), 5.0, 0.05, 0.01, {"test": True}
    )


def test_the_shipped_data_loads_with_its_provenance_and_smoothing() -> None:
    conf = twin_keys.load_confusion()
    prov = conf.provenance
    assert re.fullmatch(r"[0-9a-f]{40}", prov["commit"])
    start, stop = map(int, prov["seeds"].split(":"))
    assert start < stop <= measure_twin_confusion.HELD_OUT  # tuning seeds only
    assert prov["solver"] == "oracle" and prov["episodes"] > 0
    assert int(conf.counts.sum()) == prov["pairs"] > 0
    assert conf.prior_strength > 0 and conf.floor > 0
    np.testing.assert_allclose(conf.p.sum(axis=1), 1.0)
    assert conf.p.min() >= conf.floor * 0.5  # no pair impossible (floor, renormalised)
    data = json.loads((Path(twin_keys.__file__).with_name(twin_keys.DATA_FILE)).read_text())
    assert {"rule", "prior_strength", "prior_mismatch", "floor", "why"} <= set(data["smoothing"])


def test_smoothing_follows_counts_and_falls_back_to_the_exact_match_rule() -> None:
    conf = _confusion([("ok", "ok")] * 40 + [("grasp_lost", "ok")] * 6
                      + [("grasp_lost", "grasp_lost")] * 4)  # fmt: skip
    i = {s: k for k, s in enumerate(twin_keys.STATUSES)}
    np.testing.assert_allclose(conf.p.sum(axis=1), 1.0)
    assert conf.p[i["grasp_lost"], i["ok"]] > 0.3  # the measured confusion
    assert conf.p[i["ok"], i["ok"]] > 0.9
    # A row without pairs is the exact-match rule: own status 1, others 0.05.
    row = conf.p[i["timeout"]]
    assert row[i["timeout"]] / row[i["ok"]] == pytest.approx(1 / 0.05)
    assert conf.p.min() >= 0.005
    again = twin_keys.from_dict(json.loads(json.dumps(conf.as_dict())))
    np.testing.assert_allclose(again.p, conf.p)
    with pytest.raises(ConfigError):
        twin_keys.from_dict({"statuses": ["ok"]})


def test_a_particle_whose_twin_status_is_often_confused_with_the_real_one_keeps_weight() -> None:
    conf = _confusion([("ok", "ok")] * 40 + [("grasp_lost", "ok")] * 6
                      + [("grasp_lost", "grasp_lost")] * 4)  # fmt: skip
    real = observation_key("ok", False, np.zeros(3))
    slipped, absent, right = _state("grasp_lost"), _state("not_applicable"), _state("ok")
    # The exact-match rule: any other status costs the same.
    assert key_loglik(real, slipped) == key_loglik(real, absent) == pytest.approx(MISMATCH)
    # The confusion: the twin's slip is often the full robot's ok; absence is not.
    assert key_loglik(real, slipped, conf) > MISMATCH + 1.5
    assert key_loglik(real, absent, conf) < key_loglik(real, slipped, conf) - 1.5
    assert key_loglik(real, right, conf) > key_loglik(real, slipped, conf)
    # The grip keeps its rule.
    held = _state("ok", holding=True)
    assert key_loglik(real, held, conf) == pytest.approx(key_loglik(real, right, conf) + MISMATCH)


def test_the_real_update_weighs_by_the_confusion_and_a_search_by_the_exact_match(
    monkeypatch,
) -> None:
    conf = _confusion([("grasp_lost", "ok")] * 20)
    d = ManipulationPOMDP("opendrawer", twin_keys="confusion")
    d.confusion = conf
    a = d.action_space().discretized[0]
    monkeypatch.setattr(d, "need_worlds", lambda: None)
    states = [_state("ok"), _state("grasp_lost")]
    key = observation_key("ok", False, np.zeros(3))
    from strug_manip.domains.manipulation.state import ManipObservation

    real = ManipObservation(key, np.zeros((3, 3)), "", news=False)  # a cloud, no news
    ll = d.obs_loglik_many(real, states, a)
    assert ll[1] > ll[0]  # the measured twin slips are the full robot's ok
    search = ManipObservation(key, None, "")
    np.testing.assert_allclose(d.obs_loglik_many(search, states, a), [0.0, MISMATCH])
    d.confusion = None  # the match rule
    np.testing.assert_allclose(d.obs_loglik_many(real, states, a), [0.0, MISMATCH])


def test_a_real_stop_on_the_way_to_the_part_is_no_evidence(monkeypatch) -> None:
    """The full robot's reach met the cabinet (``cabinet_moved``, holding the object)
    where every twin, which has no arm on the way, ran to the part: the key weighs no
    particle (OpenDoor episode 10187 dropped its true model on such a key)."""
    d = ManipulationPOMDP("opendoor")
    a = d.action_space().discretized[0]
    monkeypatch.setattr(d, "need_worlds", lambda: None)
    states = [_state("ok"), _state("cabinet_moved", holding=True)]
    key = observation_key("cabinet_moved", True, np.array([0.05, 0.02, 0.0]))
    from strug_manip.domains.manipulation.state import ManipObservation

    way = ManipObservation(key, np.zeros((3, 3)), "", news=False, on_the_way=True)
    np.testing.assert_allclose(d.obs_loglik_many(way, states, a), [0.0, 0.0])
    at_part = ManipObservation(key, np.zeros((3, 3)), "", news=False)
    ll = d.obs_loglik_many(at_part, states, a)
    assert ll[0] < ll[1] <= 0.0


def test_a_real_pick_or_place_on_the_table_weighs_no_object_motion(monkeypatch) -> None:
    """Where the hand carried the object to or from the table is the full robot's: a
    real Pick's key weighs its status and grip, not the object's motion (OpenDoor
    10166 dropped its true model on one); a Place into a part, and every key inside a
    search, weigh it."""
    d = ManipulationPOMDP("opendoor")
    monkeypatch.setattr(d, "need_worlds", lambda: None)
    monkeypatch.setattr(d, "check_action", lambda a: a)  # no episode: no catalogue
    moved = ManipState(0, None, 1, observation_key("ok", True, np.array([0.15, 0.0, 0.0])))
    still = _state("ok", holding=True)
    key = observation_key("ok", True, np.array([0.55, 0.15, 0.25]))
    from strug_manip.domains.manipulation.state import ManipObservation

    real = ManipObservation(key, np.zeros((3, 3)), "", news=False)
    pick = ManipAction("Pick", grasp="side")
    np.testing.assert_allclose(d.obs_loglik_many(real, [moved, still], pick), [0.0, 0.0])
    search = ManipObservation(key, None, "")
    ll = d.obs_loglik_many(search, [moved, still], pick)
    assert ll[0] < -10.0 and ll[1] < ll[0]
    place = ManipAction("Place", 0)
    ll = d.obs_loglik_many(real, [moved, still], place)
    assert ll[1] < ll[0] < -10.0


def test_the_rule_is_chosen_by_argument_then_environment_then_default(monkeypatch) -> None:
    monkeypatch.delenv(twin_keys.TWIN_KEYS_ENV, raising=False)
    assert twin_keys.twin_keys_rule() == twin_keys.DEFAULT_TWIN_KEYS
    monkeypatch.setenv(twin_keys.TWIN_KEYS_ENV, "match")
    assert twin_keys.twin_keys_rule() == "match"
    assert ManipulationPOMDP("opendoor").confusion is None
    assert twin_keys.twin_keys_rule("confusion") == "confusion"
    assert ManipulationPOMDP("opendoor", twin_keys="confusion").confusion is not None
    with pytest.raises(UnknownNameError):
        twin_keys.twin_keys_rule("exact")


def test_the_tool_counts_health_pairs_and_refuses_held_out_seeds(tmp_path: Path) -> None:
    steps = [{"twin_status": "ok", "real_status": "ok"},
             {"twin_status": "grasp_lost", "real_status": "ok"},
             {"twin_status": None, "real_status": "ok"}]  # fmt: skip
    pairs, missing = measure_twin_confusion.pairs_of([{"report": {"health": {"steps": steps}}}])
    assert pairs == [("ok", "ok"), ("grasp_lost", "ok")] and missing == 1
    with pytest.raises(SystemExit):
        measure_twin_confusion.main(["--seeds", "9190:9210", "--runs", str(tmp_path)])
