"""What the ROS transport asks of a simulator node (``ros.sim_node``): the episode's set-up as
one atomic parameter request, the check that only one simulator answers on our names, and its
per-step physics and contact statuses."""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from pic4rl_sim.interfaces import DIAGNOSTICS, QosKind, bridge_qos
from pic4rl_sim.node.ros_interfaces import profile
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.node import Node
from rclpy.serialization import deserialize_message

from ..errors import SimConflict
from ..readings import cdr, decode
from .ros_topics import Topic
from .transport import EpisodeRequest

#: How the ROS graph names a node whose name record has not arrived yet.
_UNNAMED = "_NODE_NAME_UNKNOWN_"


def episode_request(request: EpisodeRequest) -> SetParametersAtomically.Request:
    """``seed``, ``start_pose`` and ``goal`` of the sim node, set at once (empty: sampled), and
    its ``world_variant`` when the request names one (the node rebuilds its world)."""
    start = [] if request.start is None else [float(v) for v in request.start]
    goal = [] if request.goal is None else request.goal.as_list()
    params = [
        ParameterMsg(name="seed", value=ParameterValue(
            type=ParameterType.PARAMETER_INTEGER, integer_value=int(request.seed))),
        ParameterMsg(name="start_pose", value=ParameterValue(
            type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=start)),
        ParameterMsg(name="goal", value=ParameterValue(
            type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=goal)),
    ]
    if request.world_variant is not None:
        params.append(ParameterMsg(name="world_variant", value=ParameterValue(
            type=ParameterType.PARAMETER_INTEGER, integer_value=int(request.world_variant))))
    return SetParametersAtomically.Request(parameters=params)


def check_one_sim(node: Node, sim_node: str, goal_topic: str, pose_topic: str) -> None:
    """``SimConflict`` when a second simulator answers on our names (a forgotten
    ``pic4rl-sim``), so that frames and bags would mix two worlds: more than one node
    named like ``sim_node`` publishes the goal or the pose topic, or the pose topic
    (which only a simulator or a robot's driver publishes) has a second publisher whose
    node the graph cannot name yet (DDS may lose a node's name record while several
    participants start). A graph query: cheap, once an episode."""
    sim = node.resolve_topic_name(sim_node)
    for role, topic in (("goal", goal_topic), ("pose", pose_topic)):
        nodes = [f"{info.node_namespace.rstrip('/')}/{info.node_name}"
                 for info in node.get_publishers_info_by_topic(topic)]
        twins = [name for name in nodes if name == sim or (
            role == "pose" and _UNNAMED in name)]
        if len(twins) > 1:
            shown = " and ".join(name if _UNNAMED not in name else "a node not yet named"
                                 for name in twins)
            raise SimConflict(
                f"{len(twins)} simulator nodes publish {topic} in ROS domain "
                f"{node.context.get_domain_id()}: {shown} (a pic4rl-sim left "
                "running?); stop all but one, or give each its own namespace "
                "(-r __ns:=/robot2) or ROS_DOMAIN_ID")


def subscribe_status(node: Node, faults: dict[int, str], contacts: set[int]) -> Topic:
    """Our sim's per-step ``diagnostics`` statuses (``pic4rl_sim.node``): an ERROR physics
    status says the physics diverged and the robot was put back at its start; its reason goes
    to ``faults`` under the step's stamp (ns); a contact status above OK (the robot touched
    something) puts the stamp in ``contacts``. The returned topic holds the last status's
    stamp. Read from the CDR bytes (``cdr.statuses``: no message objects built each step)."""
    from pic4rl_sim.node.messages import CONTACT_STATUS, PHYSICS_STATUS  # only with our sim

    entry = Topic(DIAGNOSTICS.name, DIAGNOSTICS.type)
    error, ok = DiagnosticStatus.ERROR[0], DiagnosticStatus.OK[0]

    def on_status(data: bytes) -> None:
        read = cdr.statuses(data)
        if read is None:  # not little-endian plain CDR: rclpy's deserialization
            msg = deserialize_message(data, DiagnosticArray)
            read = decode.stamp_ns(msg.header), [(s.level[0], s.name, s.message)
                                                 for s in msg.status]
        stamp_ns, statuses = read
        for level, name, message in statuses:
            if name == PHYSICS_STATUS:
                entry.stamp_ns = stamp_ns
                if level == error:
                    faults[stamp_ns] = message
            elif name == CONTACT_STATUS and level != ok:
                contacts.add(stamp_ns)

    sub = node.create_subscription(DiagnosticArray, DIAGNOSTICS.name, on_status,
                                   profile(bridge_qos(QosKind.RELIABLE)), raw=True)
    entry.name = sub.topic_name
    return entry


def settle(faults: dict[int, str], contacts: set[int], before_ns: int,
           stamp_ns: int) -> tuple[str | None, bool]:
    """A step's statuses, from after ``before_ns`` to ``stamp_ns`` (ns), taken out of
    ``faults`` and ``contacts`` with every older one: the first fault's reason (``None``: none)
    and whether the robot touched anything."""
    void = {s: faults.pop(s) for s in sorted(s for s in faults if s <= stamp_ns)}
    reasons = [reason for s, reason in void.items() if s > before_ns]
    touched = {s for s in contacts if s <= stamp_ns}
    contacts -= touched
    return (reasons[0] if reasons else None), any(s > before_ns for s in touched)
