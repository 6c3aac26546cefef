"""qtree_benchmarks.task: variants, the paper's claims, reports and the README block."""

import json
from pathlib import Path

import pytest
from qtree_benchmarks.task.readme import BEGIN, END, replace_section, section
from qtree_benchmarks.task.report import markdown
from qtree_benchmarks.task.summary import paper_claims, summarize
from qtree_benchmarks.task.variants import Variant, sweep_variants

RESULTS = Path(__file__).resolve().parents[4] / 'benchmarks' / 'results'


def test_variants_blank_what_does_not_apply_and_the_sweep_has_each_setting_once() -> None:
    assert Variant.make('LRND', 'positive-q', 'episode', 1) == Variant('LRND', '-', '-', 1)
    assert Variant.make('RND', 'positive-q', 'episode', 1) == Variant('RND', '-', '-', 0, '-', 0.0)
    assert (
        Variant.make('H-LRND', 'positive-q', 'episode', 7).label == 'H-LRND [positive-q, window 7]'
    )
    assert Variant.make('H-EG', 'not-failed', 'step', 50).is_default
    assert not Variant.make('H-EG', 'not-failed', 'step', 1).is_default
    sweep = sweep_variants()
    counts = {p: sum(v.policy == p for v in sweep) for p in ('RND', 'LRND', 'H-LRND', 'H-EG')}
    assert counts == {'RND': 1, 'LRND': 2, 'H-LRND': 4, 'H-EG': 8}
    assert len({v.label for v in sweep}) == len(sweep)
    assert sum(v.is_default for v in sweep) == 5  # one default row per policy
    # the steady rule and β of eq. (11) (#31 item 2): one more row per value, not for RND
    wider = sweep_variants(steady_rules=('no-new-edge', 'q-bar'), betas=(1e-3, 0.05))
    assert {p: sum(v.policy == p for v in wider) for p in counts} == {
        'RND': 1, 'LRND': 8, 'H-LRND': 16, 'H-EG': 32,
    }  # fmt: skip
    assert sum(v.is_default for v in wider) == 5 and len({v.label for v in wider}) == len(wider)
    literal = Variant.make('H-EG', 'not-failed', 'step', 1, 'q-bar', 0.05)
    assert literal.label == 'H-EG [not-failed, coin/step, window 1, q-bar, beta 0.05]'
    assert literal.training_kwargs()['steady_rule'] == 'q-bar'
    assert literal.training_kwargs()['beta'] == 0.05
    old_record = {'policy': 'LRND', 'hlrnd_rule': '-', 'epsilon_coin': '-', 'steady_episodes': 1}
    assert Variant.of_record(old_record) == Variant.make('LRND', 'not-failed', 'step', 1)
    with pytest.raises(ValueError, match='steady rule'):
        Variant.make('H-EG', 'not-failed', 'step', 1, 'folklore')
    with pytest.raises(ValueError, match='beta'):
        Variant.make('H-EG', 'not-failed', 'step', 1, 'q-bar', 0.0)
    assert sweep_variants(('H-EG',), (3,)) == [
        Variant('H-EG', r, c, 3) for r in ('not-failed', 'positive-q') for c in ('step', 'episode')
    ]
    with pytest.raises(ValueError, match='rule'):
        Variant.make('H-LRND', 'positive', 'step', 50)


def _record(policy: str, episodes: int, mp_calls: int, first: int, **readings) -> dict:
    v = Variant.make(policy, readings.get('rule', 'not-failed'), 'step', 50)
    return {'scenario': 's1', 'policy': policy, 'variant': v.label, 'hlrnd_rule': v.hlrnd_rule,
            'epsilon_coin': v.epsilon_coin, 'steady_episodes': v.steady_episodes, 'seed': 0,
            'sequence': ['O1', 'T'], 'optimal': True, 'episodes': episodes, 'mp_calls': mp_calls,
            'planner_runs_fresh': 5, 'first_optimal_episode': first, 'converged': True,
            'wall_time_s': 0.0, 'extraction': 'eq19'}  # fmt: skip


def test_claims_say_where_the_paper_ordering_and_fig4_hold() -> None:
    rows = summarize([
        _record('LRND', 500, 85, 34), _record('H-LRND', 498, 85, 25), _record('H-EG', 518, 85, 26),
        _record('H-LRND', 114, 58, 20, rule='positive-q'),
        _record('H-EG', 100, 40, 12, rule='positive-q'),
    ])  # fmt: skip
    claims = {c['hlrnd_rule']: c for c in paper_claims(rows)}
    default, positive = claims['not-failed'], claims['positive-q']
    assert default['default'] and not positive['default']
    assert not default['order_episodes'] and not default['order_mp_calls']
    assert not default['fig4'] and not default['fig5']
    assert default['first_optimal'] == {'LRND': 34, 'H-LRND': 25, 'H-EG': 26}
    assert positive['order_episodes'] and positive['order_mp_calls'] and positive['fig4']
    assert positive['episodes']['LRND'] == 500  # LRND has no rule: shared by both readings


def test_committed_markdown_is_what_the_committed_json_gives() -> None:
    """benchmark.md holds exactly the default command's report (regenerated from its JSON)."""
    data = json.loads((RESULTS / 'benchmark.json').read_text())
    meta = data['meta']
    assert meta['trainings'] == 50 and meta['max_episodes'] == 5000 and meta['seed'] == 0
    assert meta['readings'] == {'hlrnd_rule': 'not-failed', 'epsilon_coin': 'step',
                                'steady_episodes': 50, 'steady_rule': 'no-new-edge',
                                'beta': 0.001}  # fmt: skip
    assert {r['policy'] for r in data['summary']} == {'RND', 'LRND', 'H-LRND', 'H-EG', 'H-EG-SET'}
    rows = summarize(data['records'])
    assert (RESULTS / 'benchmark.md').read_text() == markdown(rows, meta)


def test_readme_block_is_generated_from_the_json_and_replaced_in_place() -> None:
    data = json.loads((RESULTS / 'benchmark.json').read_text())
    block = section(data, None)
    assert block.startswith(BEGIN) and block.endswith(END)
    assert '| S1 (4) | exact set search |' in block
    text = replace_section('intro\n' + BEGIN + '\nold\n' + END + '\nrest\n', block)
    assert text == 'intro\n' + block + '\nrest\n'
    assert replace_section('intro\n', block) == 'intro\n\n' + block + '\n'
    readme = (RESULTS.parents[1] / 'README.md').read_text()
    sweep = RESULTS / 'benchmark_sweep.json'
    assert section(data, json.loads(sweep.read_text()) if sweep.exists() else None) in readme


def test_a_planner_timeout_stops_the_benchmark_instead_of_counting_as_infeasible() -> None:
    """Under load a 2 s planning limit turned feasible checks into TIMEOUT = infeasible and
    changed S1's tables (xi_p 6 instead of 10); the benchmark now refuses such an answer."""
    from types import SimpleNamespace

    from qtree_benchmarks.task.runner import PLANNING_TIME_LIMIT_S, SharedOracle

    class Planner:
        def __init__(self, reason: int) -> None:
            self.reason = reason

        def check(self, object_id: str, relocated: list[str]) -> SimpleNamespace:
            return SimpleNamespace(feasible=False, reason=self.reason)

    oracle = SharedOracle('s1', 'planner')
    oracle._inner = Planner(205)  # SCENE_COLLISION: a geometric answer, memoised
    assert oracle.feasible(('O1',), 'T') is False and oracle.planner_runs == 1
    oracle._inner = Planner(301)  # TIMEOUT
    with pytest.raises(RuntimeError, match='timed out'):
        oracle.feasible(('O2',), 'T')
    assert PLANNING_TIME_LIMIT_S >= 60.0


def test_ros_and_in_process_records_have_the_same_keys_and_reading_of_optimal() -> None:
    from types import SimpleNamespace

    from qtree_benchmarks.task.ros_runner import _record
    from qtree_benchmarks.task.runner import Task, run_task

    task = Task('s1', 'H-EG', 0, 'synthetic', 0, 20, 1.0)  # optimal level 0: no sequence at all
    in_process = run_task(task)
    result = SimpleNamespace(
        sequence=(), extraction='none', episodes=20, mp_calls=3, planner_runs=3,
        first_learned_level_episode=-1, converged=False, message='max_episodes',
        training_time=0.1,
    )  # fmt: skip
    through_ros = _record(task, result, [])
    assert list(through_ros) == list(in_process)
    assert through_ros['optimal'] is False  # an empty answer is never "optimal" (it was, via ROS)
