"""The benchmark's trainings through the ROS graph: one sim + motion planner + task planner per
scenario, goals sent one after the other (the planner's cache persists across them).

The nodes start through :mod:`qtree_node_support.orchestration`. The
action goal has no field for the readings, so only default-reading tasks can run here.
"""

from __future__ import annotations

import os
import time

from qtree_benchmarks.task.runner import Task, training_record


def run_ros(tasks: list[Task], timeout_s: float = 3600.0) -> list[dict]:
    """Run ``tasks`` (default readings only) through the ROS graph; records like ``run_task``.

    Raises:
        ValueError: a task with a non-default reading.
        TimeoutError: no answer from /retrieve_target within ``timeout_s``.
    """
    odd = [t.variant.label for t in tasks if not t.variant.is_default]
    if odd:
        raise ValueError(f'--ros runs only the default readings, not {sorted(set(odd))}')
    import rclpy
    from qtree_msgs.action import RetrieveTarget
    from qtree_msgs.msg import TrainingStats
    from qtree_node_support.orchestration import allocate_domain_id, start_node, stop_all
    from rclpy.action import ActionClient
    from rclpy.executors import SingleThreadedExecutor
    from tqdm import tqdm

    os.environ['ROS_DOMAIN_ID'] = str(allocate_domain_id())
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    rclpy.init()
    node = rclpy.create_node('qtree_benchmark')
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    stats: list = []
    node.create_subscription(TrainingStats, '/training_stats', stats.append, 10_000)
    client = ActionClient(node, RetrieveTarget, '/retrieve_target')

    def wait(future) -> None:
        deadline = time.monotonic() + timeout_s
        while not future.done() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        if not future.done():
            raise TimeoutError('no answer from /retrieve_target')

    records = []
    bar = tqdm(total=len(tasks), desc='trainings (ROS)')
    try:
        for scenario in dict.fromkeys(t.scenario for t in tasks):
            procs = [
                start_node('jaco2_sim', 'sim_node', parameters={'scenario': scenario}),
                start_node('stpik_motion_planner', 'motion_planner_node'),
                start_node('qtree_task_planner', 'task_planner_node'),
            ]
            try:
                for proc in procs:
                    proc.wait_for_log('ready', timeout_s=120.0)
                client.wait_for_server(timeout_sec=30.0)
                for task in (t for t in tasks if t.scenario == scenario):
                    stats.clear()
                    goal = RetrieveTarget.Goal(
                        policy=task.policy,
                        seed=task.seed,
                        max_episodes=task.max_episodes,
                        steady_episodes=task.steady_episodes,
                        beta=task.beta,
                    )
                    sent = client.send_goal_async(goal)
                    wait(sent)
                    done = sent.result().get_result_async()
                    wait(done)
                    result = done.result().result
                    deadline = time.monotonic() + 5.0
                    while len(stats) < result.episodes and time.monotonic() < deadline:
                        executor.spin_once(timeout_sec=0.05)
                    records.append(_record(task, result, stats))
                    bar.update(1)
            finally:
                stop_all(procs)
    finally:
        bar.close()
        node.destroy_node()
        rclpy.try_shutdown()
    return records


def _record(task: Task, result, stats: list) -> dict:
    """A benchmark record from an action result and its /training_stats messages."""
    first = next(
        (
            s.episode
            for s in stats
            if s.reached_target and len(s.episode_sequence) == task.optimal_level
        ),
        -1,
    )
    return training_record(
        task,
        policy=task.policy,
        sequence=result.sequence,
        extraction=result.extraction,
        episodes=result.episodes,
        mp_calls=result.mp_calls,
        planner_runs_fresh=result.planner_runs,
        planner_runs_real=result.planner_runs,
        first_optimal_episode=first,
        first_learned_level_episode=result.first_learned_level_episode,
        converged=result.converged,
        stop_reason=result.message,
        wall_time_s=result.training_time,
        q_bar_curve=[[s.episode, s.q_bar] for s in stats[:: max(1, len(stats) // 200)]],
    )
