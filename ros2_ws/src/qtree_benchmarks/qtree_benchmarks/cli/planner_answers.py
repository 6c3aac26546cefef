"""Record the motion planner's answers on the S1–S3 exact-search questions, or compare two records.

Usage (env.sh sourced)::

    python scripts/planner_answers.py record OUT.json [--scenarios s1 s2 s3]
    python scripts/planner_answers.py compare --before A.json [B.json ...] --after C.json [...]

``record`` writes ``{scenario: {"answers": {"set|object": [feasible, reason]}, "cpu_s": ...,
"reached_stpik": ..., "motion": ..., "level": m}}`` (see
:mod:`qtree_benchmarks.motion.answers`). ``compare`` prints the answers that
differ between the first record and any other, and the CPU-time medians of both sides (per
question the minimum over that side's records: repeated runs filter out a shared machine's
interference); it exits 1 when any answer changed.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from tqdm import tqdm

from qtree_benchmarks.motion import answers


def main() -> int:
    """Record the planner answers of S1-S3, or compare two records."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest='command', required=True)
    record = sub.add_parser('record', help='run the exact searches and write their answers')
    record.add_argument('out', type=Path)
    record.add_argument('--scenarios', nargs='+', default=list(answers.SCENARIOS))
    record.add_argument(
        '--profile', action='store_true', help='run under cProfile (CPU clock), store phases'
    )
    cmp = sub.add_parser('compare', help='compare two records (exit 1 on a changed answer)')
    cmp.add_argument('--before', type=Path, nargs='+', required=True)
    cmp.add_argument('--after', type=Path, nargs='+', required=True)
    cmp.add_argument('--out', type=Path, help='write the comparison as JSON (benchmark report)')
    args = parser.parse_args()
    if args.command == 'record':
        out = {}
        with tqdm(desc='checks', unit='check') as bar:

            def progress(text: str) -> None:
                bar.set_postfix_str(text[:60])
                bar.update()

            if args.profile:
                out = answers.profiled_answers(args.scenarios, progress)
            else:
                for name in args.scenarios:
                    out[name] = answers.exact_answers(name, progress)
        args.out.write_text(json.dumps(out, indent=1, sort_keys=True) + '\n')
        for name, part in answers.scenarios(out).items():
            print(f'{name}: level {part["level"]}, {len(part["answers"])} questions')
        print(json.dumps(answers.timing_summary(out), indent=1))
        return 0
    try:
        before = [json.loads(path.read_text()) for path in args.before]
        after = [json.loads(path.read_text()) for path in args.after]
    except (OSError, json.JSONDecodeError) as err:
        parser.error(f'cannot read the records: {err}')
    changed, missing, questions = [], [], 0
    for other in [*before[1:], *after]:
        result = answers.compare(before[0], other)
        changed += result['changed']
        missing += result['missing']
        questions = result['questions']
        print(
            f'{len(result["changed"])} answers changed of {result["questions"]}; '
            f'{len(result["missing"])} questions asked by one run only; '
            f'{result["motions_changed"]} same answers with a changed motion'
        )
        for line in result['changed'] + result['missing']:
            print('  ' + line)
    summary: dict[str, Any] = {
        'questions': questions,
        'scenarios': sorted(answers.scenarios(before[0])),
        'answers_changed': len(changed) + len(missing),
        'runs': {'before': len(before), 'after': len(after)},
    }
    for label, records in (('before', before), ('after', after)):
        summary[label] = answers.timing_summary(answers.fastest(records))
        summary[label]['profile_cpu_s'] = next(
            (r['_profile'] for r in records if '_profile' in r), {}
        )
        print(label, json.dumps(summary[label]))
    if args.out is not None:
        args.out.write_text(json.dumps(summary, indent=2) + '\n')
    return 1 if changed or missing else 0


if __name__ == '__main__':
    sys.exit(main())
