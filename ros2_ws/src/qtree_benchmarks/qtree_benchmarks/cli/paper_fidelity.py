"""Tables 1-3 against the paper, cell by cell, from a committed benchmark sweep (#31).

Reads ``benchmarks/results/benchmark_sweep.json`` (``scripts/benchmark.py --paper-sweep``) and
writes ``paper_fidelity.json`` / ``.md``: the scenes' level, ξ_p and ξ* beside the paper's; for
the ``paper`` preset (``--reading paper`` of ``scripts/benchmark.py``) the 18 cells (S1-S3 ×
LRND / H-LRND / H-εG × episodes / MP calls) with ours / paper, how many are within ±30 %, each
ordering the paper claims, the optimal shares of eq. (19) and of the fallback; every reading of
the sweep ranked; the default reading beside. No training: seconds.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from qtree_benchmarks.paths import results_dir
from qtree_benchmarks.task.fidelity import fidelity_report, markdown
from qtree_benchmarks.task.variants import READINGS


def main(argv: list[str] | None = None) -> int:
    """Write ``paper_fidelity.json`` and ``.md``; exit code 2 on a bad or missing sweep."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--from-json', type=Path, default=results_dir() / 'benchmark_sweep.json')
    parser.add_argument('--out', type=Path, default=results_dir())
    args = parser.parse_args(argv)
    try:
        data = json.loads(args.from_json.read_text())
        report = fidelity_report(data, READINGS['paper'], READINGS['default'])
    except (OSError, ValueError, KeyError, TypeError) as err:
        print(
            f'paper_fidelity: {args.from_json} is not a benchmark sweep ({err!r})', file=sys.stderr
        )
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / 'paper_fidelity.json').write_text(json.dumps(report, indent=1))
    text = markdown(report)
    (args.out / 'paper_fidelity.md').write_text(text)
    print(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
