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

    bad = (
        ['--scenes', '0'],
        ['--densities', '0.9'],
        ['--workers', '0'],
        ['--layouts', 'packed_rows,heap'],
        ['--layouts', ''],
        ['--grasp-families', 'side,side'],
        ['--grasp-families', 'from_below'],
    )
    for argv in bad:
        with pytest.raises(SystemExit):
            bench_scale.parse_args(argv)


def test_grasp_families_flag_says_what_the_planner_refuses(capsys) -> None:
    """#27: one home for the check (grasps.check_families), the flag gives its words."""
    from qtree_benchmarks.cli import bench_scale

    for text, words in (
        ('side,side', 'repeated'),
        ('from_below', "unknown grasp family 'from_below'"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            bench_scale.parse_args(['--grasp-families', text])
        assert exit_info.value.code == 2
        err = capsys.readouterr().err
        assert f"--grasp-families: '{text}': " in err and words in err
    assert bench_scale.parse_args(['--grasp-families', 'top, side']).grasp_families == (
        'top',
        'side',
    )


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


def test_layouts_and_grasp_families_name_every_record_and_row() -> None:
    from qtree_benchmarks.cli import bench_scale

    args = bench_scale.parse_args(
        ['--layouts', 'packed_ring,accessible', '--grasp-families', 'side,top']
    )
    assert args.layouts == ('packed_ring', 'accessible') and args.grasp_families == ('side', 'top')
    records = []
    for layout in ('packed_ring', 'accessible'):
        task = ScaleTask(
            8, 0.3, 0, oracle='synthetic', methods=('exact',), layout=layout,
            grasp_families=('side', 'top'),
        )  # fmt: skip
        records += run_scene(task)
    assert [r['layout'] for r in records] == ['packed_ring', 'accessible']
    assert all(
        r['grasp_families'] == ['side', 'top'] and r['too_wide_grasps'] == 0 for r in records
    )
    rows = summarize(records)
    assert [(r['layout'], r['method']) for r in rows] == [
        ('accessible', 'exact'),
        ('packed_ring', 'exact'),
    ]
    assert '| packed_ring | side+top | 8 |' in markdown(rows, _meta(records))


def test_grasp_counts_flag_a_grasp_wider_than_the_hand() -> None:
    from types import SimpleNamespace

    from qtree_benchmarks.task.scale import grasp_counts
    from qtree_scene.scene import ObjectSpec

    box = ObjectSpec('B', 'obstacle', 'box', (0.6, 0.0, 0.1), 0.0, size=(0.06, 0.15, 0.2))

    def result(yaw, family):
        return SimpleNamespace(feasible=True, approach_yaw=yaw, grasp_family=family)

    cache = SimpleNamespace(items=lambda: [
        ((frozenset(), 'B'), result(0.0, 'side')),  # fingers close along y: 150 mm across
        ((frozenset({'X'}), 'B'), result(1.5708, 'top')),  # along x: 60 mm across
        ((frozenset({'Y'}), 'B'), SimpleNamespace(feasible=False)),
    ])  # fmt: skip
    inner = SimpleNamespace(
        planner=SimpleNamespace(cache=cache), scenario=SimpleNamespace(object=lambda _: box)
    )
    assert grasp_counts(inner) == {'side_grasps': 1, 'top_grasps': 1, 'too_wide_grasps': 1}
    assert grasp_counts(object()) == {'side_grasps': 0, 'top_grasps': 0, 'too_wide_grasps': 0}
