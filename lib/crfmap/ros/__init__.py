"""crfmap live: a ROS node that refines maps or maps from scans, over ROS 2 (Cyclone DDS or rclpy) or ROS 1 (rospy).

:mod:`~crfmap.ros.node` is the shared core (``RefineNode``, ``MapNode``, ``spin``, ``refine_grid``), with
:mod:`~crfmap.ros.messages` (middleware-free messages, ``BadMessage``), :mod:`~crfmap.ros.tf_buffer` (scans placed at
their stamps through tf), :mod:`~crfmap.ros.qos`; backends :mod:`~crfmap.ros.dds` (ROS 2 wire conventions over Cyclone
DDS, ``pip install 'crfmap[ros]'``), :mod:`~crfmap.ros.rclpy_backend`, :mod:`~crfmap.ros.rospy_backend`."""
