"""The scale benchmark's core on small synthetic scenes: records, scoring, budgets, rows."""

import pytest
from qtree_benchmarks.task.scale import METHODS, ScaleTask, markdown, run_scene, summarize


def test_scene_records_are_scored_against_the_exact_search() -> None:
    task = ScaleTask(10, 0.3, 2, oracle='synthetic', learner_episodes=300, learner_time_s=5.0)
    records = run_scene(task)
    assert [r['method'] for r in records] == list(METHODS)
    exact = records[0]
    assert exact['finished'] and exact['reference'] == 'exact'
    search = records[-1]
    assert search['certified'] and search['level'] == exact['level'] and search['optimal']
    assert search['planner_runs'] < exact['planner_runs']
    rows = summarize(records)
    keys = {'n_obstacles', 'density', 'method', 'solved_share', 'optimal_share'}
    assert keys | {'planner_runs_mean', 'wall_s_mean'} <= set(rows[0])
    assert 'BLOCKER-SEARCH / exact' in markdown(rows, _meta(records))


def test_exhausted_exact_budget_falls_back_to_the_certified_bound() -> None:
    task = ScaleTask(
        30, 0.3, 1, oracle='synthetic', methods=('exact', 'BLOCKER-SEARCH'), exact_max_runs=20
    )
    exact, search = run_scene(task)
    assert not exact['finished'] and exact['budget_hit'] == 'planner_runs'
    assert exact['planner_runs'] == 20 and not exact['optimal']
    assert search['reference'].startswith('certified') and search['optimal']


def _meta(records) -> dict:
    return dict(
        oracle='synthetic',
        scenes=1,
        workers=1,
        wall_time_s=1.0,
        exact_max_runs=1,
        exact_time_s=1.0,
        learner_episodes=1,
        learner_time_s=1.0,
        search_max_runs=1,
        search_time_s=1.0,
        records=records,
    )


def test_script_rejects_bad_flags() -> None:
    from qtree_benchmarks.cli import bench_scale

    for argv in (['--scenes', '0'], ['--densities', '0.9'], ['--workers', '0']):
        with pytest.raises(SystemExit):
            bench_scale.parse_args(argv)


def test_merge_writes_one_report_from_runs_in_parts(tmp_path) -> None:
    import json

    from qtree_benchmarks.cli import bench_scale

    common = ['--oracle', 'synthetic', '--scenes', '2', '--densities', '0.15', '--out']
    for n in ('4', '6'):
        assert bench_scale.main([*common, str(tmp_path), '--n', n, '--tag', f'_{n}']) == 0
    parts = [str(tmp_path / 'scale_4.json'), str(tmp_path / 'scale_6.json')]
    assert bench_scale.main(['--merge', *parts, '--out', str(tmp_path)]) == 0
    report = json.loads((tmp_path / 'scale.json').read_text())
    assert {r['n_obstacles'] for r in report['rows']} == {4, 6}
    assert len(report['records']) == 2 * 2 * len(bench_scale.METHODS)
    assert (tmp_path / 'scale.md').exists() and (tmp_path / 'scale.png').exists()
    (tmp_path / 'bad.json').write_text('{"rows": []}')
    with pytest.raises(SystemExit, match='not a bench_scale JSON'):
        bench_scale.main(['--merge', str(tmp_path / 'bad.json'), '--out', str(tmp_path)])
