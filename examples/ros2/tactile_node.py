"""A ROS 2 node that runs tactile-rs's palpation pipeline on an image topic.

It subscribes to a `sensor_msgs/msg/Image` topic (any encoding `tactile
run` reads in a bag: rgb8, bgr8, mono8, mono16 as the GelSight and TacTip
cameras publish, cv_bridge's 8UC3, packed YUV 4:2:2, Bayer), or with
`-p compressed:=true` to a `sensor_msgs/msg/CompressedImage` topic (JPEG or
PNG, as image_transport's `compressed` transport publishes), runs
`tactile.Pipeline` on each frame and publishes:

- `~/result` (`std_msgs/msg/String`): the frame's record as JSON (the same
  fields as a line of `tactile run --out`), stamped with the input's header;
- `~/tendon_mask` (`sensor_msgs/msg/Image`, mono8): the kept region at the
  frame's size, on tendon frames.

Run it in a sourced ROS 2 workspace::

    python3 examples/ros2/tactile_node.py --ros-args \
        -r image:=/gelsight/image_raw -p models:=models -p runtime:=onnx
    python3 examples/ros2/tactile_node.py --ros-args \
        -r image:=/gelsight/image_raw/compressed -p compressed:=true

The logic (`PalpationNode.handle`) imports nothing of ROS, so it is tested
without ROS installed (crates/tactile-py/tests/test_ros_node.py); `main`
imports rclpy only when the node is started.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

import tactile

#: A `sensor_msgs/msg/Image` or `CompressedImage` (any object with its
#: fields) as an `(H, W, 3)` uint8 RGB array: the conversion `tactile run`
#: gives a bag's frames.
image_to_rgb = tactile.ros_image_to_rgb


@dataclass
class Output:
    """What the node publishes for one frame."""

    record: dict
    mask: Optional[np.ndarray]


class PalpationNode:
    """The node's logic without ROS: a pipeline over image messages."""

    def __init__(self, models: str = "models", runtime: str = "onnx") -> None:
        self.pipeline = tactile.Pipeline(models, runtime)

    def handle(self, msg: Any) -> Output:
        """One image message: its record (with the header's stamp) and, on
        a tendon frame, the kept region as a uint8 mask of the frame's size."""
        rgb = image_to_rgb(msg)
        result = self.pipeline.process(rgb)
        record = result.to_dict()
        stamp = msg.header.stamp
        record["stamp_ns"] = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        mask = (result.mask.astype(np.uint8) * 255) if result.tendon else None
        return Output(record=record, mask=mask)


def main(argv: Optional[list[str]] = None) -> None:  # pragma: no cover - needs ROS 2
    import rclpy
    from rclpy.node import Node
    from sensor_msgs.msg import CompressedImage, Image
    from std_msgs.msg import String

    rclpy.init(args=argv if argv is not None else sys.argv)

    class TactileNode(Node):
        def __init__(self) -> None:
            super().__init__("tactile")
            models = self.declare_parameter("models", "models").value
            runtime = self.declare_parameter("runtime", "onnx").value
            compressed = self.declare_parameter("compressed", False).value
            self.logic = PalpationNode(models, runtime)
            self.results = self.create_publisher(String, "~/result", 10)
            self.masks = self.create_publisher(Image, "~/tendon_mask", 10)
            # A queue of 1: a slow model skips to the newest frame.
            self.create_subscription(CompressedImage if compressed else Image, "image", self.on_image, 1)

        def on_image(self, msg: Any) -> None:
            try:
                out = self.logic.handle(msg)
            except ValueError as e:
                self.get_logger().warning(f"frame skipped: {e}")
                return
            self.results.publish(String(data=json.dumps(out.record)))
            if out.mask is not None:
                m = Image(header=msg.header, height=out.mask.shape[0], width=out.mask.shape[1],
                          encoding="mono8", is_bigendian=0, step=out.mask.shape[1],
                          data=out.mask.tobytes())
                self.masks.publish(m)

    node = TactileNode()
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.shutdown()


if __name__ == "__main__":  # pragma: no cover
    main()
