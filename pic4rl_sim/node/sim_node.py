"""The ROS 2 node ``sim``: one simulated robot that any ROS 2 tool can drive and record.

Interfaces: the table of ``pic4rl_sim.interfaces`` (relative names, so ``--ros-args -r
__ns:=/robot1`` runs several sims side by side; services with Gazebo's names).

Sim time is an integer nanosecond counter owned by this node: it starts at 0 and each control
step adds ``control_dt_s``. Every message of a step carries that stamp, published in the
table's order (each topic only while it has a subscriber: a volatile sample for nobody is
lost anyway): the scan (or, without a LiDAR, the depth image) is a step's last message. In
``lockstep`` mode each ``cmd_vel`` advances one control period; in ``realtime`` mode a
wall-clock timer steps with the latest command, or a stop once it is older than
``cmd_timeout_s`` of sim time. Each step first publishes ``diagnostics`` (the step's stamp):
its status ``sim: physics`` is OK, or ERROR with the reason when the physics diverged, which
the engine logs (through this node's logger) and answers by putting the robot back at its
start: the episode is void, and the bridge ends it as ``diverged``; its status ``sim: contact``
is WARN when the robot touched anything during the step, sensed or not, else OK (the bridge
ends the episode as a ``contact`` collision).

Episodes: set ``seed``, ``world_variant``, ``start_pose``, ``goal`` (or any parameter) with the
parameter services, whose result is the acknowledgement, then call ``reset_world``. The reset
rebuilds the engine if the robot, world, sensors or timing changed, starts the episode,
advances sim time by one control period to t0, publishes ``goal_pose`` (stamp t0), ``plan``,
``tf_static`` (the sensors' frames), ``world/markers`` and one full set of sensor messages
stamped t0 (``tf`` among them), and only then returns.
Contract: after ``reset_world`` returns, messages stamped >= ``goal_pose.header.stamp`` belong
to the new episode. A reset uses ``seed`` if it was set since the last reset, else the previous
episode's seed + 1: plain repeated resets give new, reproducible episodes. Parameters take
effect at the next ``reset_world``, except ``clock_mode``, ``real_time_factor`` and
``cmd_timeout_s``, which apply at once. A reset that cannot be done (e.g. a world that no
longer fits the start) is logged as an error and leaves the episode as it was: ``goal_pose`` is
not republished.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Twist
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.publisher import Publisher
from rclpy.timer import Timer
from rclpy.utilities import remove_ros_args
from std_srvs.srv import Empty

from pic4rl_base.errors import ConfigError
from pic4rl_base.params_file import param_rules

from ..config import (MAX_SEED, ClockConfig, ClockMode, SimConfig, WorldChoice, build_clock,
                      build_config)
from ..engine.core import Engine, StepResult, limit_command
from ..engine.geometry import Twist2D
from ..engine.sampling import check_free
from ..engine.worlds.spec import WorldSpec
from ..errors import WorldError
from ..interfaces import (CMD_VEL, DIAGNOSTICS, INTERFACE_TABLE, PAUSE_PHYSICS, RESET_WORLD,
                          STEP_TOPICS, UNPAUSE_PHYSICS, Direction, Interface)
from .messages import CONTACT_STATUS, PHYSICS_STATUS, StateMessages, episode_messages
from .parameters import NodeLogHandler, declare, rules_as_parameters, usage
from .ros_interfaces import qos_profile, ros_type

_CLOCK_KEYS = frozenset({"clock_mode", "real_time_factor", "cmd_timeout_s"})
_THROTTLE_S = 5.0
_STOP = Twist2D()


class SimNode(Node):
    """The ``sim`` node around one ``Engine``. Raises ``ConfigError``/``WorldError`` for a bad
    parameter, before anything is published."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__("sim", **kwargs)
        self._log_handler = NodeLogHandler(self)
        logging.getLogger("pic4rl_sim").addHandler(self._log_handler)
        self._table, self._values = declare(self)
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._timer: Timer | None = None
        self._pubs: dict[str, Publisher] = {}
        self._outputs: list[tuple[Publisher, Any]] = []
        self._stamp_ns = 0
        self._paused = False
        self._seed_set = False
        self._command, self._command_ns = _STOP, 0
        self._clock_config: ClockConfig = build_clock(self._values)
        self._control_dt_ns = self._cmd_timeout_ns = 0
        self._world_cache: tuple[WorldChoice, WorldSpec] | None = None
        self._config = build_config(self._values)
        episode = self._config.episode
        self._engine = Engine(self._config.robot, self._config.world.build(), self._config.engine,
                              seed=episode.seed)
        self._engine.reset(seed=episode.seed, start=episode.start, goal=episode.goal)
        self._messages = StateMessages(self._engine)
        self._episode_pubs: dict[Interface, Publisher] = {}
        self._diagnostics_pub = self._publisher(DIAGNOSTICS)
        self._status = DiagnosticArray(status=[DiagnosticStatus(
            name=name, hardware_id=self._config.robot.name)
            for name in (PHYSICS_STATUS, CONTACT_STATUS)])
        self._use_engine()
        self._publish_episode()
        self._serve()
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    def destroy_node(self) -> None:
        logging.getLogger("pic4rl_sim").removeHandler(self._log_handler)
        super().destroy_node()

    # -- parameters ------------------------------------------------------------------------

    def _validate_parameters(self, params: list[Parameter]) -> SetParametersResult:
        """Accept a change only if the whole configuration stays valid and a given start and
        goal are free in the world they will be used in."""
        proposed = dict(self._values)
        try:
            for p in params:
                if p.name in self._table:
                    proposed[p.name] = self._table[p.name].check(p.value)
            config = build_config(proposed)
            world = self._world_for(config.world)
            episode = config.episode
            if episode.start is not None:
                check_free(world, episode.start[:2], what="start_pose",
                           clearance_m=config.robot.footprint.bounding_radius_m)
            if episode.goal is not None:
                check_free(world, episode.goal, clearance_m=0.0, what="goal")
        except (ConfigError, WorldError) as err:
            return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params: list[Parameter]) -> None:
        names = {p.name for p in params if p.name in self._table}
        for p in params:
            if p.name in names:
                self._values[p.name] = self._table[p.name].check(p.value)
        self._seed_set = self._seed_set or "seed" in names
        if names & _CLOCK_KEYS:
            self._restart_clock()

    def _world_for(self, choice: WorldChoice) -> WorldSpec:
        """The world of ``choice``: the engine's own, or built once and kept for the reset."""
        if choice == self._config.world:
            return self._engine.world
        if self._world_cache is None or self._world_cache[0] != choice:
            self._world_cache = (choice, choice.build())
        return self._world_cache[1]

    # -- episodes ------------------------------------------------------------------------

    def _start_episode(self, config: SimConfig) -> None:
        """Reset (on a new engine if the robot, world, sensors or timing changed), advance
        sim time by one control period, then publish the episode's first stamp."""
        world = self._world_for(config.world)
        episode = config.episode
        if episode.start is not None:  # checked before the reset, which changes the engine
            check_free(world, episode.start[:2], what="start_pose",
                       clearance_m=config.robot.footprint.bounding_radius_m)
        seed = episode.seed if self._seed_set else (self._engine.seed + 1) % (MAX_SEED + 1)
        rebuild = config.build_key != self._config.build_key
        engine = Engine(config.robot, world, config.engine, seed=seed) if rebuild else self._engine
        engine.reset(seed=seed, start=episode.start, goal=episode.goal)
        self._engine, self._config, self._seed_set = engine, config, False
        if rebuild:
            self._messages = StateMessages(engine)
            self._use_engine()
        self._stamp_ns += self._control_dt_ns
        self._publish_episode()

    def _use_engine(self) -> None:
        """Publishers and timing for the current engine."""
        self._wire()
        self._control_dt_ns = round(self._config.engine.control_dt_s * 1e9)
        self._restart_clock()

    def _publish_episode(self) -> None:
        """Goal, plan, sensor frames (``tf_static``), markers and a full set of sensor messages,
        all with the current stamp."""
        self._command = _STOP
        messages = episode_messages(self._engine, self._stamp_ns)
        made = {topic for topic, _ in messages}
        for topic in [t for t in self._episode_pubs if t not in made]:
            self.destroy_publisher(self._episode_pubs.pop(topic))  # no stale latched message
        for topic, msg in messages:
            if topic not in self._episode_pubs:
                self._episode_pubs[topic] = self._publisher(topic)
            self._episode_pubs[topic].publish(msg)
        self._publish_state()

    def _publisher(self, topic: Interface) -> Publisher:
        return self.create_publisher(ros_type(topic.type), topic.name, qos_profile(topic))

    def _serve(self) -> None:
        """The table's subscription and services, each to its handler."""
        handlers = {CMD_VEL: self._on_cmd_vel, RESET_WORLD: self._on_reset,
                    PAUSE_PHYSICS: self._on_pause, UNPAUSE_PHYSICS: self._on_unpause}
        for interface in INTERFACE_TABLE:
            if interface.direction is Direction.SUB:
                self.create_subscription(ros_type(interface.type), interface.name,
                                         handlers[interface], qos_profile(interface))
            elif interface.direction is Direction.SRV:
                self.create_service(ros_type(interface.type), interface.name,
                                    handlers[interface])

    def _wire(self) -> None:
        """Publishers for the step topics this engine's messages hold, in publishing order."""
        held = dict(self._messages.published)
        self._outputs = []
        for topic in STEP_TOPICS:
            msg = held.get(topic)
            if msg is None:
                if topic.name in self._pubs:
                    self.destroy_publisher(self._pubs.pop(topic.name))
                continue
            if topic.name not in self._pubs:
                self._pubs[topic.name] = self._publisher(topic)
            self._outputs.append((self._pubs[topic.name], msg))

    def _on_reset(self, request: Empty.Request, response: Empty.Response) -> Empty.Response:
        try:
            self._start_episode(build_config(self._values))
        except (ConfigError, WorldError) as err:
            self.get_logger().error(f"reset_world: {err}; the episode goes on unchanged")
        return response

    # -- stepping ------------------------------------------------------------------------

    def _publish_state(self) -> None:
        """Fill the step's messages; publish each that has a subscriber (DDS sends a volatile
        sample to matched readers only: serializing one for nobody is wasted)."""
        self._messages.fill(self._engine, self._stamp_ns)
        for publisher, msg in self._outputs:
            if publisher.get_subscription_count():
                publisher.publish(msg)

    def _step(self, command: Twist2D) -> None:
        result = self._engine.step(command)  # a divergence is logged there, reset to the start
        self._stamp_ns += self._control_dt_ns
        self._publish_status(result)
        self._publish_state()

    def _publish_status(self, result: StepResult) -> None:
        """The step's physics status on ``diagnostics``, stamped like its sensor messages and
        published before them: a bridge knows the step is void before it sees the step; not
        made at all without a subscriber (as the step's messages)."""
        if not self._diagnostics_pub.get_subscription_count():
            return
        status, contact = self._status.status
        status.level = DiagnosticStatus.ERROR if result.diverged else DiagnosticStatus.OK
        status.message = result.reason if result.diverged else "ok"
        contact.level = DiagnosticStatus.WARN if result.collided else DiagnosticStatus.OK
        contact.message = "touching" if result.collided else "clear"
        stamp = self._status.header.stamp
        stamp.sec, stamp.nanosec = divmod(self._stamp_ns, 1_000_000_000)
        self._diagnostics_pub.publish(self._status)

    def _on_cmd_vel(self, msg: Twist) -> None:
        checked = limit_command(Twist2D(msg.linear.x, msg.linear.y, msg.angular.z),
                                self._engine.robot)
        if checked.problem is not None:
            self.get_logger().warning(f"cmd_vel: {checked.problem}",
                                      throttle_duration_sec=_THROTTLE_S)
        self._command, self._command_ns = checked.command, self._stamp_ns
        if self._clock_config.mode is not ClockMode.LOCKSTEP:
            return
        if self._paused:
            self.get_logger().warning("cmd_vel: physics is paused; command dropped "
                                      "(call unpause_physics)", throttle_duration_sec=_THROTTLE_S)
            return
        self._step(checked.command)

    def _on_tick(self) -> None:
        if self._paused:
            return
        stale = self._stamp_ns - self._command_ns > self._cmd_timeout_ns
        self._step(_STOP if stale else self._command)

    def _restart_clock(self) -> None:
        """Apply the clock parameters: (re)start or stop the realtime timer."""
        clock = self._clock_config = build_clock(self._values)
        self._cmd_timeout_ns = round(clock.cmd_timeout_s * 1e9)
        if self._timer is not None:
            self.destroy_timer(self._timer)
            self._timer = None
        if clock.mode is ClockMode.REALTIME:
            period_s = self._control_dt_ns * 1e-9 / clock.real_time_factor
            self._timer = self.create_timer(period_s, self._on_tick, clock=self._steady)

    def _on_pause(self, request: Empty.Request, response: Empty.Response) -> Empty.Response:
        self._paused = True
        return response

    def _on_unpause(self, request: Empty.Request, response: Empty.Response) -> Empty.Response:
        self._paused = False
        return response


def main(argv: Sequence[str] | None = None) -> int:
    """Run the sim until interrupted; exit code 2 for a bad argument or parameter."""
    args = ["pic4rl-sim", *(sys.argv[1:] if argv is None else argv)]
    try:
        extra = remove_ros_args(args)[1:]
    except _rclpy.RCLInvalidROSArgsError as err:  # an unreadable params file, say
        print(f"pic4rl-sim: {str(err).split(', at ')[0]}", file=sys.stderr)
        return 2
    if extra in (["-h"], ["--help"]):
        print(usage())
        return 0
    if extra:
        print(f"pic4rl-sim: unexpected argument {extra[0]!r}; parameters go after --ros-args "
              "(see --help)", file=sys.stderr)
        return 2
    rclpy.init(args=args)
    try:
        node = SimNode(parameter_overrides=rules_as_parameters(param_rules(args)))
    except (ConfigError, WorldError) as err:
        print(f"pic4rl-sim: {err}", file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    # The C++ events executor costs the node ~0.4 ms less CPU per lockstep step than the
    # SingleThreadedExecutor. Its spin() and spin_once() without a timeout busy-wait in
    # rclpy 7.1.6 from PyPI, hence spin_once with one.
    executor = EventsExecutor()
    executor.add_node(node)
    try:
        while executor.context.ok():
            executor.spin_once(timeout_sec=1.0)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except _rclpy.RCLError:  # a step's publish after Ctrl-C shut the context: stopping
        if executor.context.ok():
            raise
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
