"""The ROS 2 messages the node uses, as Cyclone DDS IDL types with ROS 2's wire names (needs ``crfmap[ros]``).

ROS 2 maps ``pkg/msg/Name`` to the DDS type ``pkg::msg::dds_::Name_`` (rosidl's IDL), fields in ``.msg`` order,
final extensibility: plain CDR (XCDR1). The field lists are Humble's (and Jazzy's: these messages did not change)."""
# no "from __future__ import annotations": cyclonedds reads the field types from the live annotations

from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, float64, int8, int32, sequence, uint32


def _ros_name(package, name):
    return f"{package}::msg::dds_::{name}_"


@dataclass
class Time(IdlStruct, typename=_ros_name("builtin_interfaces", "Time")):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename=_ros_name("std_msgs", "Header")):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Point(IdlStruct, typename=_ros_name("geometry_msgs", "Point")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename=_ros_name("geometry_msgs", "Quaternion")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose(IdlStruct, typename=_ros_name("geometry_msgs", "Pose")):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class Vector3(IdlStruct, typename=_ros_name("geometry_msgs", "Vector3")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Transform(IdlStruct, typename=_ros_name("geometry_msgs", "Transform")):
    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass
class TransformStamped(IdlStruct, typename=_ros_name("geometry_msgs", "TransformStamped")):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    transform: Transform = field(default_factory=Transform)


@dataclass
class TFMessage(IdlStruct, typename=_ros_name("tf2_msgs", "TFMessage")):
    transforms: sequence[TransformStamped] = field(default_factory=list)


@dataclass
class MapMetaData(IdlStruct, typename=_ros_name("nav_msgs", "MapMetaData")):
    map_load_time: Time = field(default_factory=Time)
    resolution: float32 = 0.0
    width: uint32 = 0
    height: uint32 = 0
    origin: Pose = field(default_factory=Pose)


@dataclass
class OccupancyGrid(IdlStruct, typename=_ros_name("nav_msgs", "OccupancyGrid")):
    header: Header = field(default_factory=Header)
    info: MapMetaData = field(default_factory=MapMetaData)
    # int8[] on the wire is a uint32 count then the bytes, as sequence<octet>: bytes serialise in one
    # copy, where a sequence[int8] of a 1.5-million-cell map takes over a second in pure Python
    data: sequence[int8] = field(default_factory=list)


@dataclass
class LaserScan(IdlStruct, typename=_ros_name("sensor_msgs", "LaserScan")):
    header: Header = field(default_factory=Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: sequence[float32] = field(default_factory=list)
    intensities: sequence[float32] = field(default_factory=list)


# The ROS 2 type of each kind of message the node reads or writes
TYPES = {"grid": OccupancyGrid, "metadata": MapMetaData, "scan": LaserScan, "tf": TFMessage}
