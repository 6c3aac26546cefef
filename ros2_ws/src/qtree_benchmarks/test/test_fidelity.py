"""Tables 1-3 against the paper cell by cell (#31): cells, ratios, claims, readings ranked."""

import json

import pytest
from qtree_benchmarks.task.fidelity import close_count, fidelity_report
from qtree_benchmarks.task.paper import PAPER
from qtree_benchmarks.task.variants import READINGS


def _row(scenario, policy, rule, coin, window, scale, steady=None):
    episodes, mp_calls, first = PAPER[(scenario, policy)]
    row = {
        'scenario': scenario, 'policy': policy, 'hlrnd_rule': rule, 'epsilon_coin': coin,
        'steady_episodes': window, 'trainings': 50, 'episodes': [episodes * scale, 1.0],
        'mp_calls': [mp_calls * scale, 1.0], 'first_optimal': [first * scale, 1.0],
        'first_optimal_reached': 50,
    }  # fmt: skip
    if steady is not None:  # rows written before #31 item 2 have no steady rule and beta
        row['steady_rule'], row['beta'] = steady
    return row


def _sweep(matching: int = 1, steady: tuple | None = None) -> dict:
    """Window ``matching`` matches the paper exactly (x1.0); the other of windows 1 and 50
    doubles every number (x2.0). ``steady``: the (steady rule, beta) of every row."""
    rows = []
    for window, scale in ((matching, 1.0), (50 if matching == 1 else 1, 2.0)):
        for s in ('s1', 's2', 's3'):
            rows.append(_row(s, 'LRND', '-', '-', window, scale, steady))
            for rule in ('not-failed', 'positive-q'):
                rows.append(_row(s, 'H-LRND', rule, '-', window, scale, steady))
                for coin in ('step', 'episode'):
                    rows.append(_row(s, 'H-EG', rule, coin, window, scale, steady))
    scenes = {
        s: {'level': lv, 'feasible_sequences': xi, 'optimal_sequences': 1}
        for s, lv, xi in (('s1', 4, 10), ('s2', 5, 341), ('s3', 6, 20))
    }
    record = {'scenario': 's1', 'policy': 'LRND', 'hlrnd_rule': '-', 'epsilon_coin': '-',
              'steady_episodes': 1, 'optimal': True,
              'extraction': 'best-known-fallback'}  # fmt: skip
    return {'meta': {'scenarios': scenes, 'trainings': 50}, 'summary': rows, 'records': [record]}


def test_the_reading_that_matches_the_paper_has_every_cell_close() -> None:
    report = fidelity_report(
        _sweep(), ('not-failed', 'episode', 1, 'no-new-edge', 1e-3), READINGS['default']
    )
    assert report['cells_total'] == 18 and len(report['cells']) == 18
    assert report['cells_within_30pct'] == 18
    assert all(c['ratio'] == pytest.approx(1.0) for c in report['cells'])
    assert report['default']['cells_within_30pct'] == 0  # the default's window 50: x2 everywhere
    assert report['readings'][0]['cells_within_30pct'] == 18
    assert report['readings'][-1]['cells_within_30pct'] == 0
    assert report['scenarios']['S2'] == {
        'level': 5, 'xi_p': 341, 'xi_star': 1, 'paper': {'level': 5, 'xi_p': 20, 'xi_star': 1},
    }  # fmt: skip
    assert all(c['holds'] for c in report['claims'])  # the paper's numbers keep its orderings
    shares = report['optimal_shares'][0]
    assert shares['eq19_optimal_share'] == 0.0 and shares['fallback_optimal_share'] == 1.0


def test_a_cell_is_close_within_30_percent_only() -> None:
    cells = [{'ratio': r} for r in (0.69, 0.7, 1.3, 1.31, None)]
    assert close_count(cells) == 2


def test_script_writes_the_report_and_refuses_a_file_that_is_no_sweep(tmp_path) -> None:
    from qtree_benchmarks.cli import paper_fidelity

    sweep = tmp_path / 'sweep.json'
    preset = READINGS['paper']  # its window matches, every row has its steady rule and beta
    sweep.write_text(json.dumps(_sweep(preset[2], preset[3:])))
    assert paper_fidelity.main(['--from-json', str(sweep), '--out', str(tmp_path)]) == 0
    report = json.loads((tmp_path / 'paper_fidelity.json').read_text())
    keys = {'scenarios', 'reading', 'cells', 'cells_within_30pct', 'claims'}
    assert keys <= set(report)
    assert '18 of 18 cells within ±30 %' in (tmp_path / 'paper_fidelity.md').read_text()
    (tmp_path / 'bad.json').write_text('{"summary": []}')
    assert paper_fidelity.main(['--from-json', str(tmp_path / 'bad.json')]) == 2


def test_benchmark_reading_preset_sets_the_three_readings() -> None:
    from qtree_benchmarks.cli import benchmark

    args = benchmark.parse_args(['--reading', 'paper'])
    named = (args.hlrnd_rule, args.epsilon_coin, args.steady_episodes, args.steady_rule, args.beta)
    assert named == READINGS['paper']
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--reading', 'paper', '--steady-episodes', '5'])
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--reading', 'paper', '--beta', '0.01'])
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--beta', '0'])
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--steady-rule', 'folklore'])
    with pytest.raises(SystemExit):
        benchmark.parse_args(['--reading', 'folklore'])
