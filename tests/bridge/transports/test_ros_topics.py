"""The ROS transport's subscriptions (``pic4rl_bridge.transports.ros_topics.wiring``) as pure data:
which topics, with the sim's types and QoS, and the topic a lockstep step waits for."""

from __future__ import annotations

import pytest
from pic4rl_sim.interfaces import BRIDGE_HISTORY, DEPTH_IMAGE, PLAN, SCAN, QosSettings

from pic4rl_bridge.config import EnvConfig
from pic4rl_bridge.errors import ConfigError
from pic4rl_bridge.transports.ros_topics import Topic, stale, wiring


def resolve(name: str) -> str:
    return "/" + name.strip("/")


@pytest.mark.parametrize(("sensors", "sync"), [
    ({"scan", "person"}, "scan"), ({"depth", "person"}, DEPTH_IMAGE.name),
    ({"scan", "depth", "plan"}, "scan"), ({"plan"}, "odom"), (set(), "odom")])
def test_a_step_waits_for_the_needed_sensor_the_sim_publishes_last(sensors: set[str],
                                                                    sync: str) -> None:
    assert wiring(EnvConfig(), frozenset(sensors), resolve).sync == sync


def test_types_and_qos_come_from_the_sim_table() -> None:
    wired = wiring(EnvConfig(), frozenset({"scan", "plan", "person"}), resolve)
    deep = BRIDGE_HISTORY
    assert wired.wanted == {
        "odom": ("nav_msgs/msg/Odometry", QosSettings(True, False, deep)),
        "goal_pose": ("geometry_msgs/msg/PoseStamped", QosSettings(True, True, 1)),
        PLAN.name: (PLAN.type, QosSettings(True, True, 1)),
        SCAN.name: (SCAN.type, QosSettings(False, False, deep)),
        "person/pose": ("geometry_msgs/msg/PoseStamped", QosSettings(True, False, deep))}
    assert wired.episodic == {"goal_pose", PLAN.name}
    assert list(wired.roles) == ["pose", "goal", "plan", "scan", "person"]


def test_without_a_sim_the_goal_and_plan_are_volatile_and_sensors_may_be_reliable() -> None:
    config = EnvConfig().replace(**{"ros.sim_node": "", "ros.sensor_qos": "reliable"})
    wired = wiring(config, frozenset({"scan", "plan"}), resolve)
    assert wired.wanted["goal_pose"][1] == QosSettings(True, False, BRIDGE_HISTORY)
    assert wired.wanted[PLAN.name][1] == QosSettings(True, False, BRIDGE_HISTORY)
    assert wired.wanted[SCAN.name][1] == QosSettings(True, False, BRIDGE_HISTORY)


def test_recorded_topics_join_by_their_sim_type_and_unknown_ones_are_refused() -> None:
    config = EnvConfig().replace(**{"record.enabled": True,
                                    "record.topics": ["clock", "cmd_vel", "world/markers"]})
    wired = wiring(config, frozenset({"scan"}), resolve)
    assert wired.record_cmd and "cmd_vel" not in wired.wanted
    assert wired.wanted["clock"] == ("rosgraph_msgs/msg/Clock",
                                     QosSettings(True, False, BRIDGE_HISTORY))
    assert wired.wanted["world/markers"][1] == QosSettings(True, True, 1)
    assert wired.recorded == {"/clock", "/cmd_vel", "/world/markers"}
    bad = EnvConfig().replace(**{"record.enabled": True, "record.topics": ["map"]})
    with pytest.raises(ConfigError, match="record.topics: 'map' has no known message type"):
        wiring(bad, frozenset(), resolve)


def test_plan_is_waited_for_once_an_episode() -> None:
    assert wiring(EnvConfig(), frozenset({"scan", "plan"}), resolve).once == ["plan"]
    assert wiring(EnvConfig(), frozenset({"scan"}), resolve).once == []


def test_a_recorded_only_topic_stamp_is_read_from_its_cdr_bytes() -> None:
    """Every recordable type said to start with a stamp does, on the wire; the others
    (markers, transforms) are the ones with no stamp first: a transform's is its first
    transform's, read from the message."""
    from builtin_interfaces.msg import Time
    from pic4rl_sim.node.ros_interfaces import ros_type, starts_with_stamp
    from rclpy.serialization import serialize_message

    from pic4rl_bridge.transports.ros_topics import KNOWN_TOPICS, cdr_stamp, stamp_of

    without = set()
    for topic in KNOWN_TOPICS.values():
        kind = ros_type(topic.type)
        if not starts_with_stamp(kind):
            without.add(topic.name)
            continue
        msg = kind()
        stamp = msg.clock if hasattr(msg, "clock") else msg.header.stamp
        stamp.sec, stamp.nanosec = 12, 345
        assert isinstance(stamp, Time)
        assert cdr_stamp(serialize_message(msg)) == 12_000_000_345, topic.name
    assert without == {"world/markers", "tf", "tf_static"}
    tf = ros_type("tf2_msgs/msg/TFMessage")()
    tf.transforms = [ros_type("geometry_msgs/msg/TransformStamped")()] * 2
    tf.transforms[0].header.stamp.sec, tf.transforms[0].header.stamp.nanosec = 3, 7
    assert stamp_of(tf) == 3_000_000_007
    assert stamp_of(ros_type("tf2_msgs/msg/TFMessage")()) is None


def test_a_topic_is_stale_past_the_bound_by_arrival_time() -> None:
    odom, scan = Topic("/odom", "nav_msgs/msg/Odometry"), Topic("/scan", SCAN.type)
    odom.received_s, scan.received_s = 10.0, 9.3
    assert stale([odom, scan], 0.5, 10.1) == (
        "topic /scan: no message for 0.80 s (ros.max_sensor_age_s 0.5 s)")
    assert stale([odom, scan], 0.5, 9.7) is None
    never = Topic("/depth", DEPTH_IMAGE.type)  # no message at all: infinitely old
    assert stale([never], 0.5, 0.0).startswith("topic /depth: no message for inf s")


def test_a_message_is_kept_as_bytes_and_deserialized_only_when_read(monkeypatch) -> None:
    """A step's messages are read from their CDR bytes (``cdr``): the receiver keeps the bytes
    and their stamp; rclpy's deserialization runs only when ``msg`` is read, once a message."""
    from nav_msgs.msg import Odometry
    from pic4rl_sim.interfaces import ODOM
    from rclpy.serialization import serialize_message

    from pic4rl_bridge.readings import cdr
    from pic4rl_bridge.transports import ros_topics
    from pic4rl_bridge.transports.ros_topics import receiver

    made = []
    real = ros_topics.deserialize_message
    monkeypatch.setattr(ros_topics, "deserialize_message",
                        lambda data, kind: made.append(kind) or real(data, kind))
    entry, delivered = Topic("/odom", ODOM.type), []
    entry.recorded = True
    on_message = receiver(entry, lambda topic, data, stamp: delivered.append(stamp))
    msg = Odometry()
    msg.header.stamp.sec, msg.header.stamp.nanosec = 2, 5
    msg.pose.pose.position.x = 1.5
    on_message(serialize_message(msg))
    assert (made, entry.stamp_ns, entry.count, delivered) == ([], 2_000_000_005, 1,
                                                                 [2_000_000_005])
    assert cdr.odometry(entry.data)[0].x == 1.5 and made == []
    assert entry.msg.pose.pose.position.x == 1.5 and entry.msg is entry.msg
    assert made == [Odometry]  # once for this message
    msg.pose.pose.position.x = 2.5
    on_message(serialize_message(msg))
    assert entry.msg.pose.pose.position.x == 2.5 and made == [Odometry, Odometry]
