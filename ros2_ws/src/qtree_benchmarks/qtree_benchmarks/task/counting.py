"""Size of the search space, eq. (7) of the paper, and the difficulty metrics of Sect. 3.2.2."""

from __future__ import annotations

from math import comb, factorial


def num_target_sequences(n_obstacles: int) -> int:
    """Number of sequences of k = 1..N_o distinct obstacles followed by the target, eq. (7).

    Implements eq. (7): xi_r = sum_{i=1}^{N_o} i! * C(N_o, i) (ordered selections without
    repetition). As in the paper the target alone (k = 0) is not counted; add 1 for it.

    Args:
        n_obstacles: N_o >= 0.

    Returns:
        xi_r, e.g. 1, 4, 15, 64, 325 for N_o = 1..5.

    Raises:
        ValueError: ``n_obstacles`` is negative.
    """
    if n_obstacles < 0:
        raise ValueError(f'n_obstacles must be >= 0, got {n_obstacles}')
    return sum(factorial(i) * comb(n_obstacles, i) for i in range(1, n_obstacles + 1))


def num_tree_nodes(n_obstacles: int) -> int:
    """Number of nodes of the complete Q-Tree (Figure 3): every ordered sequence of distinct
    obstacles (the root included), each also extended by the target.

    Args:
        n_obstacles: N_o >= 0.

    Returns:
        2 * sum_{k=0}^{N_o} N_o! / (N_o - k)!: every node whose sequence holds only obstacles
        (the root is k = 0), and one target leaf below each of them; 2, 4, 10 for N_o = 0, 1, 2.

    Raises:
        ValueError: ``n_obstacles`` is negative.
    """
    if n_obstacles < 0:
        raise ValueError(f'n_obstacles must be >= 0, got {n_obstacles}')
    obstacle_nodes = sum(
        factorial(n_obstacles) // factorial(n_obstacles - k) for k in range(0, n_obstacles + 1)
    )  # includes the root (k = 0)
    return 2 * obstacle_nodes  # each obstacle node (and the root) has one target leaf


def difficulty(n_optimal: int, n_feasible: int, n_obstacles: int) -> tuple[float, float]:
    """Difficulty metrics of Sect. 3.2.2: xi*/xi_r (optimum) and xi/xi_r (any solution).

    Args:
        n_optimal: xi*, number of feasible target sequences of minimal length.
        n_feasible: xi, number of feasible target sequences.
        n_obstacles: N_o, used for xi_r of eq. (7).

    Returns:
        (xi*/xi_r, xi/xi_r) as fractions (multiply by 100 for the paper's percentages).
    """
    total = num_target_sequences(n_obstacles)
    return n_optimal / total, n_feasible / total
