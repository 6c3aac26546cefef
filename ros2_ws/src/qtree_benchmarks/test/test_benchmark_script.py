"""scripts/benchmark.py end to end on the synthetic tables (fast; no motion planner)."""

import json
from pathlib import Path

import pytest
from qtree_benchmarks.cli import benchmark


def test_synthetic_benchmark_writes_tables_and_plots(tmp_path: Path) -> None:
    code = benchmark.main(
        [
            '--oracle',
            'synthetic',
            '--trainings',
            '2',
            '--workers',
            '1',
            '--scenarios',
            's1',
            's2',
            '--out',
            str(tmp_path),
            '--tag',
            't',
        ]
    )
    assert code == 0
    data = json.loads((tmp_path / 'benchmark_t.json').read_text())
    assert data['meta']['scenarios']['s1']['level'] == 4
    assert data['meta']['scenarios']['s2']['level'] == 5
    assert len(data['records']) == 2 * 2 * 5  # scenarios x trainings x default policies
    for record in data['records']:
        if record['policy'] != 'RND':
            assert record['sequence'][-1] == 'T' and record['mp_calls'] > 0
        assert record['planner_runs_fresh'] <= record['mp_calls']
        assert bool(record['q_bar_curve']) == (record['seed'] == 0)  # first seed only
    rows = {(r['scenario'], r['policy']): r for r in data['summary']}
    assert rows[('s1', 'H-EG-SET')]['optimal_share'] == 1.0
    assert rows[('s1', 'H-EG')]['paper'] == [115, 34, 16]
    report = (tmp_path / 'benchmark_t.md').read_text()
    assert '| H-εG | ' in report and '115 / 34 / 16' in report
    assert '| exact set search (BFS, reference) | ' in report
    for name in ('fig4_first_optimal', 'fig5_episodes', 'mp_calls', 'q_bar_curves'):
        assert (tmp_path / f't_{name}.png').stat().st_size > 1000


def test_bad_arguments_are_rejected() -> None:
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--trainings', '0'])
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--ros', '--oracle', 'synthetic'])


def test_tag_names_the_outputs_with_one_separator() -> None:
    """``--tag X`` writes benchmark_X.* (was: benchmarkX.md); a leading '_' is not doubled."""
    assert benchmark.parse_args(['--tag', 'dev']).tag == 'dev'
    assert benchmark.parse_args(['--tag', '_dev']).tag == 'dev'
    assert benchmark.parse_args([]).tag == ''
    assert benchmark.parse_args(['--paper-sweep']).tag == 'sweep'
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--ros', '--hlrnd-rule', 'positive-q'])
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--sweep-windows', '0'])


def test_default_tables_from_a_sweep_equal_the_default_command(tmp_path: Path) -> None:
    """--from-json on a sweep writes, byte for byte, what the default command writes."""
    common = ['--oracle', 'synthetic', '--trainings', '2', '--workers', '1', '--scenarios', 's1']
    assert benchmark.main([*common, '--out', str(tmp_path / 'direct')]) == 0
    assert benchmark.main([*common, '--paper-sweep', '--out', str(tmp_path / 'sweep')]) == 0
    sweep = tmp_path / 'sweep' / 'benchmark_sweep.json'
    assert (tmp_path / 'sweep' / 'benchmark_sweep.md').read_text().count('★') >= 5
    code = benchmark.main([*common, '--from-json', str(sweep), '--out', str(tmp_path / 'derived')])
    assert code == 0
    direct = (tmp_path / 'direct' / 'benchmark.md').read_text()
    assert (tmp_path / 'derived' / 'benchmark.md').read_text() == direct
    records = json.loads((tmp_path / 'derived' / 'benchmark.json').read_text())['records']
    fields = ('policy', 'seed', 'sequence', 'episodes', 'mp_calls', 'first_optimal_episode')
    again = json.loads((tmp_path / 'direct' / 'benchmark.json').read_text())['records']
    assert [[r[k] for k in fields] for r in records] == [[r[k] for k in fields] for r in again]
    bad = benchmark.main([*common, '--trainings', '3', '--from-json', str(sweep)])
    assert bad == 2


def test_the_json_keeps_one_record_per_line_and_reads_back_equal() -> None:
    from qtree_benchmarks.cli.benchmark import dumps_with_one_record_per_line

    data = {'meta': {'a': [1, 2]}, 'summary': [{'s': 1.5}], 'records': [{'x': 1}, {'y': 'z'}]}
    text = dumps_with_one_record_per_line(data)
    assert json.loads(text) == data
    assert '{"x":1},\n{"y":"z"}' in text  # one line per record
    assert json.loads(dumps_with_one_record_per_line({'meta': {}, 'records': []})) == {
        'meta': {},
        'records': [],
    }
