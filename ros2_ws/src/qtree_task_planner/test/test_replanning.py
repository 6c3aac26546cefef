"""Re-planning during the execution (#32): the core helpers and the goal's recovery loop, with a
scripted execution and a hand-built feasibility table instead of the ROS graph."""

from __future__ import annotations

import dataclasses
import threading
from types import SimpleNamespace
from typing import Any

import pytest
from qtree_msgs.action import RetrieveTarget
from qtree_scene.message import scene_msg
from qtree_scene.scenario import load_scenario
from qtree_task_planner.goal_checks import settings_from_goal
from qtree_task_planner.goal_run import GoalContext, execute_with_replans, scene_watch, train
from qtree_task_planner.oracle import TableOracle
from qtree_task_planner.replanning import (
    PrefixOracle,
    ReuseCounter,
    combined,
    kept_prefix,
    replan_cause,
)
from qtree_task_planner.sequence_execution import CANCELED, OK, REPLAN

Result = RetrieveTarget.Result
S1 = load_scenario('s1')


def test_replan_causes_name_the_reason_and_the_object() -> None:
    assert replan_cause('O3', 304, 'x') == "SCENE_CHANGED relocating 'O3': x"
    assert replan_cause('O3', 305, 'y').startswith("GRASP_FAILED relocating 'O3'")
    assert replan_cause('O3', 205, 'z') == "'O3' no longer feasible (reason 205): z"
    assert replan_cause('O3', 302, 'stopped') is None  # EXECUTION_FAILED ends the goal
    assert replan_cause('O3', 301, 'timeout') is None


def test_kept_prefix_is_the_executed_order_of_what_stays_relocated() -> None:
    assert kept_prefix(['O2', 'O3', 'O1'], ['O1', 'O2', 'O3']) == ('O2', 'O3', 'O1')
    assert kept_prefix(['O2', 'O3'], ['O2']) == ('O2',)


def test_prefix_oracle_asks_after_the_prefix() -> None:
    inner = TableOracle({'T': [{'O1', 'O2'}]})
    oracle = PrefixOracle(inner, ('O1',))
    assert not inner.feasible(('O2',), 'T')
    assert oracle.feasible(('O2',), 'T') and oracle.answer(('O2',), 'T').feasible
    assert oracle.planner_runs == inner.planner_runs  # the wrapped oracle's attributes


@dataclasses.dataclass
class Trained:
    """The fields of a TrainingResult that :func:`combined` reads."""

    sequence: tuple
    episodes: int
    mp_calls: int
    planner_runs: int
    wall_time_s: float


def test_combined_sums_the_trainings_and_prefixes_the_sequence() -> None:
    first = Trained(('O2', 'O1', 'T'), 10, 5, 4, 1.0)
    second = Trained(('O1', 'T'), 3, 2, 1, 0.5)
    total = combined([first, second], ('O2',))
    assert total.sequence == ('O2', 'O1', 'T')
    assert (total.episodes, total.mp_calls, total.planner_runs) == (13, 7, 5)
    assert total.wall_time_s == pytest.approx(1.5)


def scene(statuses: dict[str, str] | None = None, moved: dict[str, tuple] | None = None) -> Any:
    poses = {k: (v, (0.0, 0.0, 0.0, 1.0)) for k, v in (moved or {}).items()}
    return scene_msg(S1, poses, statuses or {})


class Graph:
    """A goal's context with a scripted execution: ``steps`` is one function per run, called
    with (graph, sequence, prefix) and returning (status, message)."""

    def __init__(self, oracle: TableOracle, steps: list, **goal: Any) -> None:
        self.scene = scene()
        self.steps = list(steps)
        self.runs: list[tuple[tuple[str, ...], tuple[str, ...]]] = []
        self.executed: list[str] = []
        self.feedback: list[Any] = []
        self.replans: list[dict[str, Any]] = []  # the /task_planner/replans events
        self.handle = SimpleNamespace(
            request=None, is_cancel_requested=False, publish_feedback=self.feedback.append
        )
        fields = dict(policy='H-EG-SET', max_episodes=300, execute=True) | goal
        defaults = dict(
            seed=0,
            alpha=0.5,
            gamma=0.9,
            epsilon0=1.0,
            epsilon_min=1e-4,
            beta=1e-3,
            steady_episodes=20,
            feedback_every=1,
            max_replans=3,
        )
        self.settings = settings_from_goal(SimpleNamespace(**(defaults | fields)))
        self.ctx = GoalContext(
            scene=lambda: self.scene,
            planner=None,
            param=lambda name: 0.2,
            stopping=threading.Event(),
            publish_stats=lambda *a: None,
            publish_tree=lambda *a: None,
            execution=self,
            oracle=oracle,
        )

    def publish_replan(self, **fields: Any) -> None:
        self.replans.append(fields)

    def run(self, sequence, timeout_s, stop, prefix=(), changed=None):
        self.runs.append((tuple(sequence), tuple(prefix)))
        self.executed = list(prefix)
        return self.steps.pop(0)(self, tuple(sequence), tuple(prefix))

    def go(self) -> tuple[int, str, Any, bool]:
        movable = ('O1', 'O2', 'O3', 'O4', 'O5', 'T')
        code, message, first = train(
            self.handle, self.ctx, self.settings, movable, 'T', self.ctx.oracle
        )
        assert code == Result.SUCCESS, message
        return execute_with_replans(self.handle, self.ctx, self.settings, first, self.scene)


def relocate(graph: Graph, ids: tuple[str, ...]) -> None:
    """The scripted arm relocated ``ids`` (the scene shows them RELOCATED)."""
    graph.executed += list(ids)
    graph.scene = scene(
        {o: 'relocated' for o in graph.executed}, moved=getattr(graph, 'moved', None)
    )


def all_done(graph: Graph, sequence, prefix) -> tuple[str, str]:
    relocate(graph, sequence)
    return OK, ''


def test_a_grasp_failure_replans_from_the_same_state_and_succeeds() -> None:
    def grasp_fails(graph, sequence, prefix):
        return REPLAN, f'GRASP_FAILED relocating {sequence[0]!r}: grasp failed (attempt 1)'

    graph = Graph(TableOracle({'T': [{'O1'}]}), [grasp_fails, all_done])
    code, message, result, executed = graph.go()
    assert code == Result.SUCCESS and executed, message
    assert graph.runs[0] == (('O1', 'T'), ()) and graph.runs[1] == (('O1', 'T'), ())
    assert graph.ctx.replan_causes == ["GRASP_FAILED relocating 'O1': grasp failed (attempt 1)"]
    assert '1 re-plans' in message and result.sequence == ('O1', 'T')
    assert graph.feedback[-1].replans == 1 and graph.feedback[-1].replan_causes


def test_a_scene_change_keeps_the_relocations_done_and_plans_the_rest_after_them() -> None:
    oracle = TableOracle({'T': [{'O1'}], 'O1': [{'O2'}]})

    def o5_moves_in_front_of_t(graph, sequence, prefix):
        relocate(graph, sequence[:2])  # O2 and O1 done, T undone
        graph.moved = {'O5': (0.7, 0.0, 0.06)}
        graph.scene = scene({o: 'relocated' for o in graph.executed}, graph.moved)
        oracle.requirements['T'] = [frozenset({'O1', 'O5'})]  # O5 now blocks T
        return REPLAN, "SCENE_CHANGED relocating 'T': 'O5' moved 0.207 m"

    graph = Graph(oracle, [o5_moves_in_front_of_t, all_done])
    code, message, result, _ = graph.go()
    assert code == Result.SUCCESS, message
    assert graph.runs[0][0] == ('O2', 'O1', 'T')
    assert graph.runs[1] == (('O5', 'T'), ('O2', 'O1'))  # kept, then the re-planned rest
    assert result.sequence == ('O2', 'O1', 'O5', 'T')
    started, planned = graph.replans  # one re-plan: its start and its new plan, recorded
    assert started['phase'] == 'started' and started['replan'] == 1
    assert started['cause'].startswith('SCENE_CHANGED') and started['reused_answers'] == -1
    assert planned['phase'] == 'planned' and planned['kept_ids'] == ['O2', 'O1']
    assert planned['sequence'] == ['O5', 'T'] and planned['planner_runs'] >= 0


def test_max_replans_ends_the_goal_with_replan_limit_naming_the_cause() -> None:
    def fails(graph, sequence, prefix):
        return REPLAN, f'GRASP_FAILED relocating {sequence[0]!r}: attempt {len(graph.runs)}'

    graph = Graph(TableOracle({'T': [{'O1'}]}), [fails, fails], max_replans=1)
    code, message, _, executed = graph.go()
    assert code == Result.REPLAN_LIMIT and not executed
    assert message.startswith('max_replans=1 re-plans made, one more needed: GRASP_FAILED')
    assert 'attempt 2' in message and len(graph.ctx.replan_causes) == 1
    graph = Graph(TableOracle({'T': [{'O1'}]}), [fails], max_replans=0)
    assert graph.go()[0] == Result.REPLAN_LIMIT and graph.ctx.replan_causes == []


def test_no_sequence_after_the_change_is_no_solution_saying_what_changed() -> None:
    oracle = TableOracle({'T': [{'O1'}]})

    def t_now_unreachable(graph, sequence, prefix):
        relocate(graph, sequence[:1])
        oracle.requirements['T'] = []  # nothing frees T any more
        return REPLAN, "SCENE_CHANGED relocating 'T': 'X1' added"

    code, message, result, _ = Graph(oracle, [t_now_unreachable]).go()
    assert code == Result.NO_SOLUTION
    assert "after SCENE_CHANGED relocating 'T': 'X1' added" in message
    assert "1 relocations kept ['O1']" in message
    assert result.sequence[:1] == ('O1',)


def test_a_target_gone_from_the_clutter_is_no_solution() -> None:
    def target_removed(graph, sequence, prefix):
        graph.scene = scene({'T': 'relocated'})
        return REPLAN, "SCENE_CHANGED relocating 'O1': 'T' removed"

    code, message, _, _ = Graph(TableOracle({'T': [{'O1'}]}), [target_removed]).go()
    assert code == Result.NO_SOLUTION and "target 'T' is not in the clutter" in message


def test_a_cancel_during_the_replanning_ends_canceled() -> None:
    def cancel_then_fail(graph, sequence, prefix):
        graph.handle.is_cancel_requested = True
        return REPLAN, "GRASP_FAILED relocating 'O1': x"

    code, _, _, _ = Graph(TableOracle({'T': [{'O1'}]}), [cancel_then_fail]).go()
    assert code == Result.CANCELED

    def canceled(graph, sequence, prefix):
        return CANCELED, 'canceled during the relocation'

    assert Graph(TableOracle({'T': [{'O1'}]}), [canceled]).go()[0] == Result.CANCELED


def test_the_watch_names_what_moved_between_steps_but_not_what_was_carried() -> None:
    current = {'scene': scene()}
    changed = scene_watch(lambda: current['scene'], scene())
    assert changed([]) == []
    current['scene'] = scene({'O1': 'relocated'}, moved={'O1': (0.0, 0.5, 0.06)})
    assert changed(['O1']) == []  # carried away and placed by us
    current['scene'] = scene(
        {'O1': 'relocated'}, moved={'O1': (0.0, 0.5, 0.06), 'O4': (0.45, -0.3, 0.07)}
    )
    assert changed(['O1']) == [f"'O4' moved {_dist(S1.object('O4').position, (0.45, -0.3)):.3f} m"]


def _dist(a, b) -> float:
    return ((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2) ** 0.5


def test_reuse_counter_counts_distinct_questions_answered_from_the_cache() -> None:
    counter = ReuseCounter()
    counter.count(('O1',), 'T', True)
    counter.count(('O1',), 'T', True)  # the same question again: not a second reuse
    counter.count(('O2', 'O1'), 'O3', False)
    counter.count(('O1', 'O2'), 'O3', True)  # same set: asked before, planned then
    counter.count((), 'O1', True)
    assert counter.reused == 2
    counter.reset()
    counter.count(('O1',), 'T', True)
    assert counter.reused == 1


class CachingOracle(TableOracle):
    """A table oracle whose answers count as from the motion planner's cache when in
    ``cached`` (the answers it kept across a scene change)."""

    def __init__(self, requirements, cached) -> None:
        super().__init__(requirements)
        self.reuse, self.cached = ReuseCounter(), cached

    def answer(self, relocated, object_id):
        self.reuse.count(relocated, object_id, (frozenset(relocated), object_id) in self.cached)
        return super().answer(relocated, object_id)


def test_each_replan_reports_the_answers_it_reused() -> None:
    kept = {(frozenset({'O1'}), 'T'), (frozenset(), 'O1')}
    oracle = CachingOracle({'T': [{'O1'}]}, kept)

    def grasp_fails(graph, sequence, prefix):
        return REPLAN, f'GRASP_FAILED relocating {sequence[0]!r}: grasp failed (attempt 1)'

    graph = Graph(oracle, [grasp_fails, grasp_fails, all_done])
    code, message, _, _ = graph.go()
    assert code == Result.SUCCESS, message
    assert len(graph.ctx.reused_answers) == 2  # one per re-plan, both asked the kept pairs
    assert all(n >= 1 for n in graph.ctx.reused_answers)
    assert graph.ctx.reused_answers[0] <= len(kept)
    # the feedback of the second re-plan's training carries the first re-plan's count
    assert list(graph.feedback[-1].reused_answers) == graph.ctx.reused_answers[:1]


def test_prefix_oracle_asks_clear_zone_questions_after_the_prefix_too() -> None:
    asked = []

    class WithClearZone:
        planner_runs = 3

        def clear_zone_feasible(self, relocated, object_id):
            asked.append((relocated, object_id))
            return True

    oracle = PrefixOracle(WithClearZone(), ('O2',))
    assert oracle.clear_zone_feasible(('O3',), 'T') is True
    assert asked == [(('O2', 'O3'), 'T')] and oracle.planner_runs == 3
    bare = PrefixOracle(TableOracle({}), ('O2',))
    assert getattr(bare, 'clear_zone_feasible', None) is None  # then ask_clear uses feasible()
