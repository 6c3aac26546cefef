"""Replay a recorded qtree-tamp run (one MCAP file written by the recorder).

Modes (exactly one):

  --summary   print the run metadata, the topics with types and message counts, the duration and
              the training result (last /training_stats, best sequence, number of planner events).
  --rerun     convert the run to a Rerun recording with the live view's layout, without ROS:
              save it to --rrd OUT.rrd (default: the log's path with suffix .rrd), or --spawn a
              viewer (with --rrd too: save, then open the file in a viewer). --screenshot PNG
              also renders the saved view at the end of the run with a headless Rerun viewer
              (needs a graphics stack, e.g. Mesa lavapipe: WGPU_BACKEND=vulkan).
  --tree-png  draw the learned Q-tree (last /qtree message) like the paper's Figure 3 to a PNG:
              levels as rows, Q on the edges, extracted sequence highlighted, --top-k nodes
              per level (default 4) with a note of what was left out.
  --publish   republish the recorded topics on a live ROS 2 graph with their original timing
              (like `ros2 bag play`): CDR bytes unchanged, QoS from the recorded
              offered_qos_profiles (transient local where recorded so). --rate scales the speed,
              --topics selects topics. Topics whose type has no Python typesupport (e.g.
              tf2_msgs) are skipped with a warning. Uses the ROS_DOMAIN_ID of the environment.

Bad input (missing file, not an MCAP, corrupt, another robot, no readable topic) ends with a
one-line message on stderr and exit code 2. A truncated log (killed recorder) is replayed up to
its last complete chunk, with a warning. Channels with unknown schemas are skipped with a warning.

Examples:
  python scripts/replay.py run.mcap --summary
  python scripts/replay.py run.mcap --rerun --rrd run.rrd && rerun run.rrd
  python scripts/replay.py --tree-png tree.png run.mcap
  python scripts/replay.py run.mcap --publish --rate 2 --topics /joint_states /scene
"""

from __future__ import annotations

import argparse
import datetime
import logging
import subprocess
import sys
import time
from pathlib import Path

import yaml

from qtree_recorder.mcap_reader import McapRun, ReplayError, open_run
from qtree_recorder.playback import publish

EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130
PROG = 'replay.py'
_LOG = logging.getLogger(PROG)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line options (see the module docstring, shown by ``--help``)."""
    head, _, tail = __doc__.partition('\n\n')
    parser = argparse.ArgumentParser(
        prog=PROG, description=head, epilog=tail, formatter_class=argparse.RawTextHelpFormatter
    )
    parser.add_argument('log', type=Path, help='the run log (.mcap)')
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument('--summary', action='store_true', help='print what the log contains')
    mode.add_argument('--rerun', action='store_true', help='convert to a Rerun recording')
    mode.add_argument('--publish', action='store_true', help='republish on a live ROS graph')
    mode.add_argument('--tree-png', type=Path, metavar='PNG', help='draw the learned Q-tree')
    parser.add_argument('--top-k', type=int, default=4, help='--tree-png: nodes per level')
    rerun = parser.add_argument_group('--rerun options')
    rerun.add_argument('--rrd', type=Path, help='output .rrd (default: LOG with suffix .rrd)')
    rerun.add_argument('--spawn', action='store_true', help='show the run in a Rerun viewer')
    rerun.add_argument('--urdf', type=Path, help='robot URDF if the log has no /robot_description')
    rerun.add_argument('--screenshot', type=Path, metavar='PNG', help='render the .rrd to PNG')
    publish = parser.add_argument_group('--publish options')
    publish.add_argument(
        '--rate', type=float, default=1.0, help='speed factor, 2 = twice as fast (default: 1)'
    )
    publish.add_argument('--topics', nargs='+', metavar='TOPIC', help='topics to publish')
    publish.add_argument(
        '--wait-subscribers',
        type=float,
        default=2.0,
        metavar='S',
        help='wait up to S seconds for a subscriber before the first message (default: 2)',
    )
    parser.add_argument('-q', '--quiet', action='store_true', help='no progress bar')
    args = parser.parse_args(argv)
    if args.rate <= 0:
        parser.error('--rate must be positive')
    if args.top_k < 1:
        parser.error('--top-k must be >= 1')
    return args


def print_summary(run: McapRun) -> None:
    """Print metadata, topics, duration and the training result of ``run`` to stdout."""
    state = 'TRUNCATED (read up to its last complete chunk)' if run.truncated else 'complete'
    print(f'log: {run.path} [{state}]')
    print(f'profile: {run.profile or "?"}')
    for name, record in run.metadata.items():
        if name == 'rosbag2':
            bag = yaml.safe_load(record.get('serialized_metadata', '')) or {}
            shown = {k: bag.get(k) for k in ('version', 'ros_distro', 'message_count')}
            print(f'metadata {name}: ' + ', '.join(f'{k}={v}' for k, v in shown.items()))
        else:
            print(f'metadata {name}: ' + ', '.join(f'{k}={v}' for k, v in record.items()))
    start = datetime.datetime.fromtimestamp(run.start_ns * 1e-9, tz=datetime.UTC)
    print(f'duration: {run.duration_s:.3f} s (start {start.isoformat(timespec="seconds")})')
    print(f'topics: {len(run.topics)}, messages: {run.message_count}')
    width = max((len(t) for t in run.topics), default=5)
    type_width = max((len(t.type) for t in run.topics.values()), default=4)
    for topic in sorted(run.topics.values(), key=lambda t: t.name):
        print(f'  {topic.name:<{width}}  {topic.type:<{type_width}}  {topic.count:>7}')
    _print_training(run)
    _print_world(run)


def _print_world(run: McapRun) -> None:
    """The changing world (#32): scene events, SCENE_CHANGED / GRASP_FAILED answers and
    re-plans, with their times from the start of the log.
    """
    from qtree_recorder.world_changes import TOPICS, timeline

    lines = list(timeline(run.messages(TOPICS), run.start_ns))
    print(f'changing world: {len(lines)} events' if lines else 'changing world: no events')
    for line in lines:
        print(line)


def _print_training(run: McapRun) -> None:
    last = None
    episodes = 0
    for msg in run.messages(['/training_stats']):
        last, episodes = msg.message, episodes + 1
    feasible = infeasible = 0
    for msg in run.messages(['/motion_planner/events']):
        if msg.message.feasible:
            feasible += 1
        else:
            infeasible += 1
    print('training:')
    if last is None:
        print('  no /training_stats in the log')
    else:
        print(
            f'  episodes recorded: {episodes} (last episode {last.episode}, policy {last.policy})'
        )
        print(
            f'  last: Q̄={last.q_bar:.4g} nodes={last.nodes} edges={last.edges} '
            f'MP calls={last.mp_calls} planner runs={last.planner_runs} ε={last.epsilon:.4g}'
        )
        best = ' -> '.join(last.best_sequence) or '(none reaches the target)'
        print(f'  best sequence: {best}')
    total = feasible + infeasible
    print(f'  planner events: {total} ({feasible} feasible, {infeasible} infeasible)')


def convert(run: McapRun, *, rrd: Path | None, spawn: bool, urdf: Path | None, quiet: bool) -> int:
    """Convert ``run`` to Rerun through the live view's :class:`RunView`; return messages logged.

    Args:
        run: the scanned log.
        rrd: output file (None: stream to a viewer).
        spawn: open a viewer (on the file when ``rrd`` is given).
        urdf: URDF to use when the log has no ``/robot_description``.
        quiet: no progress bar.
    """
    from tqdm import tqdm

    from qtree_recorder.rerun_view import TOPICS, RunView

    if '/robot_description' not in run.topics and urdf is None:
        urdf = _default_urdf()
    view = RunView(mode='save' if rrd else 'spawn', rrd_path=rrd, urdf_path=urdf)
    wanted = [t for t in TOPICS if t in run.topics]
    total = sum(run.topics[t].count for t in wanted)
    count = 0
    with tqdm(total=total, unit='msg', disable=True if quiet else None, file=sys.stderr) as bar:
        for msg in run.messages(wanted):
            view.on_message(msg.topic, msg.message, msg.log_time_ns)
            count += 1
            bar.update()
    view.close()
    if view.error_count:
        _LOG.warning('%d Rerun logging errors (see above)', view.error_count)
    if rrd is not None:
        print(f'wrote {rrd} ({count} messages)')
        if spawn:
            subprocess.Popen(['rerun', str(rrd)], start_new_session=True)
    return count


def screenshot(rrd: Path, png: Path, *, settle_s: float = 15.0, port: int = 0) -> None:
    """Render ``rrd`` (default layout, time cursor at the end) to ``png`` in a headless viewer.

    Args:
        rrd: the recording.
        png: output image (1920×1080).
        settle_s: time given to the viewer to load and lay out the graph [s] (3 s left the
            Q-tree panel empty on a loaded machine).
        port: gRPC port of the headless viewer (0: a free one).

    Raises:
        ReplayError: the viewer could not start or render (no graphics adapter...).
    """
    import socket

    from rerun.experimental import ViewerClient

    if port == 0:
        with socket.socket() as sock:
            sock.bind(('127.0.0.1', 0))
            port = sock.getsockname()[1]
    try:
        client = ViewerClient.spawn(headless=True, port=port, hide_welcome_screen=True)
    except Exception as err:
        raise ReplayError(f'cannot start a headless Rerun viewer: {err}') from None
    try:
        client.open(str(Path(rrd).resolve()))
        time.sleep(settle_s)
        png.parent.mkdir(parents=True, exist_ok=True)
        client.save_screenshot(str(Path(png).resolve()))
    except Exception as err:
        raise ReplayError(f'headless Rerun viewer failed to render {rrd}: {err}') from None
    finally:
        client.quit()
    print(f'wrote {png}')


def _default_urdf() -> Path | None:
    try:
        from jaco2_description.model import urdf_path
    except ImportError:
        _LOG.warning('no /robot_description in the log and no jaco2_description: no robot shown')
        return None
    return urdf_path()


def main(argv: list[str] | None = None) -> int:
    """Run the selected mode; return the process exit code."""
    args = parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format=f'{PROG}: warning: %(message)s')
    try:
        run = open_run(args.log)
        if args.summary:
            print_summary(run)
        elif args.rerun:
            rrd = args.rrd or (None if args.spawn else args.log.with_suffix('.rrd'))
            convert(run, rrd=rrd, spawn=args.spawn, urdf=args.urdf, quiet=args.quiet)
            if args.screenshot is not None:
                if rrd is None:
                    raise ReplayError(
                        '--screenshot needs a saved recording (drop --spawn or add --rrd)'
                    )
                screenshot(rrd, args.screenshot)
        elif args.tree_png is not None:
            from qtree_recorder.qtree_figure import tree_png_from_run

            print(f'wrote {tree_png_from_run(run, args.tree_png, top_k=args.top_k)}')
        else:
            publish(run, rate=args.rate, topics=args.topics, wait_s=args.wait_subscribers)
    except ReplayError as err:
        print(f'{PROG}: error: {err}', file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    return 0


if __name__ == '__main__':
    sys.exit(main())
