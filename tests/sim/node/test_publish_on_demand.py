"""A step publishes only the topics someone subscribes to: the node in this process, its
publishes counted, one listener subscribing to one topic and then another."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.publisher import Publisher
from ros_helpers import next_domain

from pic4rl_sim.engine.geometry import Twist2D
from pic4rl_sim.node.sim_node import SimNode

pytestmark = pytest.mark.integration


@pytest.fixture
def sim_here(arena_mjcf: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple]:
    """(node, a listener node, spin_until, the topics published so far)."""
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    sent: list[str] = []
    publish = Publisher.publish
    monkeypatch.setattr(Publisher, "publish",
                        lambda self, msg: (sent.append(self.topic_name), publish(self, msg))[1])
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=next_domain())
    node = SimNode(context=context, parameter_overrides=[
        Parameter("world", value=str(arena_mjcf)), Parameter("clock_mode", value="lockstep")])
    listener = rclpy.create_node("listener", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(listener)

    def spin_until(done: Callable[[], bool]) -> None:
        for _ in range(500):
            if done():
                return
            executor.spin_once(timeout_sec=0.02)
        raise AssertionError("timed out")

    try:
        yield node, listener, spin_until, sent
    finally:
        executor.shutdown()
        listener.destroy_node()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def test_a_step_publishes_only_the_topics_that_have_a_subscriber(sim_here: tuple) -> None:
    node, listener, spin_until, sent = sim_here
    odom: list[Odometry] = []
    listener.create_subscription(Odometry, "odom", odom.append, 10)
    spin_until(lambda: node._pubs["odom"].get_subscription_count() == 1)
    sent.clear()
    node._step(Twist2D(0.2, 0.0, 0.0))
    assert sent == ["/odom"]  # not clock, ground_truth, imu/data, scan or diagnostics
    spin_until(lambda: bool(odom))
    stamp = odom[-1].header.stamp
    assert stamp.sec * 1_000_000_000 + stamp.nanosec == node._stamp_ns

    status: list[DiagnosticArray] = []
    listener.create_subscription(DiagnosticArray, "diagnostics", status.append, 10)
    spin_until(lambda: node._diagnostics_pub.get_subscription_count() == 1)
    sent.clear()
    node._step(Twist2D(0.2, 0.0, 0.0))
    assert sent == ["/diagnostics", "/odom"]  # the status first, as before
    spin_until(lambda: bool(status) and len(odom) == 2)
    assert status[-1].status[0].message == "ok"
