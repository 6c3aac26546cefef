"""The paper's numbers (Tables 1-3, Sect. 4) that every benchmark table is printed beside."""

from __future__ import annotations

# Tables 1-3: (episodes to steady state, MP calls, first optimal episode)
PAPER: dict[tuple[str, str], tuple[int, int, int]] = {
    ('s1', 'LRND'): (144, 42, 20),
    ('s1', 'H-LRND'): (119, 37, 18),
    ('s1', 'H-EG'): (115, 34, 16),
    ('s2', 'LRND'): (1079, 236, 96),
    ('s2', 'H-LRND'): (1007, 218, 77),
    ('s2', 'H-EG'): (717, 188, 74),
    ('s3', 'LRND'): (3496, 665, 181),
    ('s3', 'H-LRND'): (2868, 588, 160),
    ('s3', 'H-EG'): (1189, 331, 156),
}
PAPER_RND = {'s1': 'optimal in about 60 % of 50 trials', 's2': 'not solved', 's3': 'not solved'}
PAPER_XI = {'s1': 10, 's2': 20, 's3': 20}  # feasible target sequences xi_p (Sect. 4)
PAPER_POLICIES = ('LRND', 'H-LRND', 'H-EG')  # the order the paper claims, worst to best


def paper_text(scenario: str, policy: str) -> str:
    """The paper's "Ep / MP / 1st*" for a row, or what the paper says instead."""
    if policy == 'RND':
        return PAPER_RND.get(scenario, '–')
    if policy == 'H-EG-SET':
        return 'ours (not in the paper)'
    if policy == 'H-EG-SET-PLAIN':
        return 'ablation: H-EG-SET without optimism'
    numbers = PAPER.get((scenario, policy))
    return ' / '.join(map(str, numbers)) if numbers else '–'
