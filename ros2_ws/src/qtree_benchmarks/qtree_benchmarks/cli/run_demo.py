"""The qtree-tamp demo: the whole story on one scenario, as a user's orchestration script would.

Starts the recorder, the Jaco² simulator, the STPIK motion planner and the Q-Tree task planner as
separate processes (``ros2 run`` when a ``ros2`` command is on PATH, otherwise the same executable
found through the ament index), sends a ``RetrieveTarget`` goal, shows the training progress,
executes the learned sequence on the simulated arm, stops every node cleanly and prints where the
MCAP log and the Rerun recording are.

Exit codes: 0 success; 1 a node died, the goal failed or timed out; 2 bad command line;
130 interrupted (Ctrl-C), after every node was stopped.

Example:
    ./qtree demo --scenario s2 --policy H-LRND --seed 3 --headless
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from qtree_node_support.orchestration import LaunchError, NodeProcess, start_node, stop_all

from qtree_benchmarks.demo_goal import DemoError, retrieve_target

POLICIES = ('RND', 'LRND', 'H-LRND', 'H-EG', 'H-EG-SET', 'H-EG-SET-PLAIN')
READY_TIMEOUT_S = 60.0


@dataclass(frozen=True)
class RunFiles:
    """Where one run writes its outputs."""

    directory: Path
    mcap: Path
    rrd: Path
    logs: Path


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Parse the command line (``--help`` documents every option)."""
    parser = argparse.ArgumentParser(
        description='Learn and execute the shortest relocation sequence on a scenario.'
    )
    parser.add_argument(
        '--scenario', default='s1', help='installed scenario (s1, s2, s3) or a YAML path'
    )
    parser.add_argument('--policy', default='H-EG', choices=POLICIES, help='exploration policy')
    parser.add_argument('--seed', type=int, default=0, help='seed of the training (reproducible)')
    parser.add_argument(
        '--max-episodes', type=int, default=5000, help='Ep_max, the episode budget (> 0)'
    )
    parser.add_argument(
        '--no-execute', action='store_true', help='train only; do not move the simulated arm'
    )
    parser.add_argument(
        '--execution-mode',
        default='closed_loop',
        choices=('closed_loop', 'open_loop'),
        help='closed_loop: STPIK in the loop at 100 Hz (the paper, default); open_loop: whole '
        'trajectories',
    )
    parser.add_argument(
        '--headless', action='store_true', help='no Rerun viewer: write the .rrd file only'
    )
    parser.add_argument(
        '--output-dir', type=Path, default=Path('runs'), help='where MCAP, .rrd and logs go'
    )
    parser.add_argument(
        '--timeout', type=float, default=900.0, help='give up after this many seconds'
    )
    parser.add_argument(
        '--scene-events',
        default='',
        metavar='YAML',
        help='test events for the simulator (#32), e.g. "[{kind: move, object: O5, xy: [0.7, '
        '0.0], hand_within_m: 0.2}]" (format in jaco2_sim/scene_events.py): watch a recovery',
    )
    args = parser.parse_args(argv)
    if args.max_episodes <= 0:
        parser.error('--max-episodes must be > 0')
    if args.timeout <= 0:
        parser.error('--timeout must be > 0')
    if args.scene_events.strip():
        why = scene_events_problem(args.scenario, args.scene_events)
        if why:
            parser.error(f'--scene-events: {why}')
    return args


def scene_events_problem(scenario: str, text: str) -> str:
    """Why the simulator would refuse the scene events ``text`` on ``scenario`` ('' if not).

    Checked before any node starts, with the simulator's own parser, so that a typo is a
    command-line error and not a node log line.
    """
    from jaco2_sim.exceptions import SceneEventError
    from jaco2_sim.scene_events import parse_events
    from qtree_scene.exceptions import ScenarioError
    from qtree_scene.scenario import load_scenario

    try:
        parse_events(text, load_scenario(scenario))
    except (SceneEventError, ScenarioError) as err:
        return str(err)
    return ''


def run_files(output_dir: Path, scenario: str) -> RunFiles:
    """Name this run's files after the date and the scenario."""
    tag = Path(scenario).stem if scenario.endswith(('.yaml', '.yml')) else scenario
    stem = f'qtree_{time.strftime("%Y%m%d-%H%M%S")}_{tag}'
    directory = output_dir.resolve()
    directory.mkdir(parents=True, exist_ok=True)
    return RunFiles(
        directory,
        directory / f'{stem}.mcap',
        directory / f'{stem}.rrd',
        directory / f'{stem}_logs',
    )


def viewer_available() -> bool:
    """True when a graphical Rerun viewer can be spawned here."""
    return bool(os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY'))


def start_graph(args: argparse.Namespace, files: RunFiles) -> list[NodeProcess]:
    """Start recorder, simulator, motion planner and task planner; wait until each is ready.

    The recorder starts first and is stopped last, so it records the whole run.
    """
    metadata = {
        'scenario': args.scenario,
        'policy': args.policy,
        'seed': args.seed,
        'max_episodes': args.max_episodes,
        'execute': not args.no_execute,
        'execution_mode': args.execution_mode,
        'scene_events': args.scene_events,
    }
    rerun_mode = 'save' if args.headless else 'spawn'
    sim_parameters: dict[str, Any] = {'scenario': args.scenario}
    if args.scene_events.strip():
        sim_parameters['scene_events'] = args.scene_events
    specs: list[tuple[str, str, dict[str, Any]]] = [
        (
            'qtree_recorder',
            'recorder_node',
            {
                'output_dir': str(files.directory),
                'file_name': files.mcap.name,
                'scenario': args.scenario,
                'run_metadata': json.dumps(metadata),
                'rerun_mode': rerun_mode,
                'rrd_path': str(files.rrd),
            },
        ),
        ('jaco2_sim', 'sim_node', sim_parameters),
        (
            'stpik_motion_planner',
            'motion_planner_node',
            {'seed': args.seed, 'execution_mode': args.execution_mode},
        ),
        ('qtree_task_planner', 'task_planner_node', {}),
    ]
    nodes: list[NodeProcess] = []
    try:
        for package, executable, parameters in specs:
            nodes.append(
                start_node(package, executable, parameters=parameters, log_dir=files.logs)
            )
        for node in nodes:
            node.wait_for_log('ready', READY_TIMEOUT_S)
    except LaunchError:
        stop_all(nodes)
        raise
    return nodes


def report(result: Any) -> None:
    """Print the training result and where the run's files are."""
    sequence = ' → '.join(result.sequence) or '(none)'
    print(f'\nresult:    {"success" if result.success else "FAILED"} — {result.message}')
    print(f'sequence:  {sequence}')
    print(
        f'episodes:  {result.episodes}   MP calls: {result.mp_calls}   planner runs: '
        f'{result.planner_runs}   first episode reaching the learned level: '
        f'{result.first_learned_level_episode}   extraction: {result.extraction}   '
        f'converged: {result.converged}   executed: {result.executed}'
    )
    for number, cause in enumerate(getattr(result, 'replan_causes', ()), start=1):
        reused = list(getattr(result, 'reused_answers', ()))
        kept = f' ({reused[number - 1]} answers reused)' if number <= len(reused) else ''
        print(f're-plan {number}: {cause}{kept}')


def print_files(files: RunFiles) -> None:
    """Say where the MCAP log, the Q-tree picture, the Rerun recording and the node logs are."""
    print(f'MCAP log:  {files.mcap}{"" if files.mcap.exists() else "  (missing!)"}')
    if files.mcap.exists():
        from qtree_recorder.mcap_reader import ReplayError
        from qtree_recorder.qtree_figure import tree_png_beside

        try:
            print(f'Q-tree:    {tree_png_beside(files.mcap)}')
        except ReplayError as err:
            print(f'Q-tree:    not drawn ({err})')
    print(f'Rerun:     {files.rrd}{"" if files.rrd.exists() else "  (not written)"}')
    print(f'node logs: {files.logs}')
    print(f'open with: rerun {files.mcap.name}   or   python scripts/replay.py --summary ...')


def main(argv: list[str] | None = None) -> int:
    """Run the demo; return the process exit code."""
    args = parse_args(argv)
    if not args.headless and not viewer_available():
        print('no display found: running headless (the Rerun recording goes to a .rrd file)')
        args.headless = True
    files = run_files(args.output_dir, args.scenario)
    nodes: list[NodeProcess] = []
    code = 0
    try:
        print(f'starting the node graph (logs in {files.logs}); execution: {args.execution_mode}')
        nodes = start_graph(args, files)
        print('nodes ready: ' + ', '.join(node.name for node in nodes))
        result = retrieve_target(args, nodes)
        report(result)
        code = 0 if result.success else 1
    except KeyboardInterrupt:
        print('\ninterrupted: stopping every node')
        code = 130
    except (DemoError, LaunchError) as error:
        print(f'error: {error}', file=sys.stderr)
        code = 1
    finally:
        exit_codes = stop_all(nodes)
        unclean = {name: rc for name, rc in exit_codes.items() if rc not in (0, -2)}
        if unclean:
            print(f'nodes that did not exit cleanly: {unclean}', file=sys.stderr)
            code = code or 1
        if nodes:
            print_files(files)
    return code


if __name__ == '__main__':
    sys.exit(main())
