"""Tables from an existing benchmark JSON without training again (``benchmark.py --from-json``).

Every training is seeded and the planner's answers are geometric, so the records of a variant in
a paper sweep are the records the one-reading command trains for it (same tasks, same order):
the default Tables 1-3 can be written from a sweep's default rows.
"""

from __future__ import annotations

import copy
from typing import Any

from qtree_benchmarks.task.variants import Variant


def select(data: dict, variants: list[Variant], scenarios: list[str]) -> tuple[list[dict], dict]:
    """The records of ``variants`` on ``scenarios`` and the scenario info for them.

    ``real_planner_runs`` of a scenario is recomputed for the selection: the reference's runs
    (the JSON's total minus every record's) plus the selected records'.

    Raises:
        ValueError: a requested scenario or variant is not in the JSON.
    """
    wanted = set(variants)
    records = [r for r in data['records']
               if r['scenario'] in scenarios and Variant.of_record(r) in wanted]  # fmt: skip
    info: dict[str, Any] = {}
    for name in scenarios:
        if name not in data['meta']['scenarios']:
            raise ValueError(f'scenario {name!r} is not in the JSON')
        present = {Variant.of_record(r) for r in records if r['scenario'] == name}
        missing = wanted - present
        if missing:
            raise ValueError(f'{name}: no records of {sorted(v.label for v in missing)}')
        source = copy.deepcopy(data['meta']['scenarios'][name])
        every = sum(r['planner_runs_real'] for r in data['records'] if r['scenario'] == name)
        chosen = sum(r['planner_runs_real'] for r in records if r['scenario'] == name)
        source['real_planner_runs'] = source['real_planner_runs'] - every + chosen
        info[name] = source
    return records, info
