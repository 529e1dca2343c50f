"""A ROS 2 node that runs tactile-rs's palpation pipeline on an image topic.

It subscribes to a `sensor_msgs/msg/Image` topic (any encoding `tactile
run` reads in a bag: rgb8, bgr8, mono8, mono16 as the GelSight and TacTip
cameras publish, cv_bridge's 8UC3, packed YUV 4:2:2, Bayer), or with
`-p compressed:=true` to a `sensor_msgs/msg/CompressedImage` topic (JPEG or
PNG, as image_transport's `compressed` transport publishes), or to a video
topic, decoded as its packets arrive by `tactile.VideoDecoder`: with
`-p video:=foxglove` a `foxglove_msgs/msg/CompressedVideo` topic (H.264,
H.265, VP9 or AV1, as ROS 2 video encoders and the Foxglove bridge
publish), with `-p video:=ffmpeg` `ffmpeg_image_transport`'s
`FFMPEGPacket` topic, with `-p video:=h264` `h264_image_transport`'s
`h264_msgs/msg/Packet` topic, or with `-p video:=compressed` a
`CompressedImage` topic carrying video (format `h264`, as GStreamer's
ROS 2 sink publishes). It runs `tactile.Pipeline`
on each frame and publishes:

- `~/result` (`std_msgs/msg/String`): the frame's record as JSON (the same
  fields as a line of `tactile run --out`), stamped with the input's header;
- `~/tendon_mask` (`sensor_msgs/msg/Image`, mono8): the kept region at the
  frame's size, on tendon frames.

Run it in a sourced ROS 2 workspace::

    python3 examples/ros2/tactile_node.py --ros-args \
        -r image:=/gelsight/image_raw -p models:=models -p runtime:=onnx
    python3 examples/ros2/tactile_node.py --ros-args \
        -r image:=/gelsight/image_raw/compressed -p compressed:=true
    python3 examples/ros2/tactile_node.py --ros-args \
        -r image:=/gelsight/video -p video:=foxglove

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
        self.video: Optional[tactile.VideoDecoder] = None

    def handle(self, msg: Any) -> Output:
        """One image message: its record (with the header's stamp) and, on
        a tendon frame, the kept region as a uint8 mask of the frame's size."""
        stamp = msg.header.stamp
        return self.process(image_to_rgb(msg), int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec))

    def handle_video(self, msg: Any) -> list[Output]:
        """One video message (a CompressedVideo, with `timestamp` and
        `format`; an FFMPEGPacket, with `header` and `encoding`; an
        h264_msgs Packet, with `header`, always H.264; a CompressedImage of
        format `h264`, with `header` and `format`): the outputs of the
        frames it completes, normally its own."""
        stamp = msg.timestamp if hasattr(msg, "timestamp") else msg.header.stamp
        if self.video is None:
            codec = getattr(msg, "format", None) or getattr(msg, "encoding", None) or "h264"
            self.video = tactile.VideoDecoder(codec)
        frames = self.video.decode(msg.data, int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec))
        return [self.process(f.image, f.stamp_ns) for f in frames]

    def process(self, rgb: np.ndarray, stamp_ns: int) -> Output:
        result = self.pipeline.process(rgb)
        record = result.to_dict()
        record["stamp_ns"] = stamp_ns
        mask = (result.mask.astype(np.uint8) * 255) if result.tendon else None
        return Output(record=record, mask=mask)


def main(argv: Optional[list[str]] = None) -> None:  # pragma: no cover - needs ROS 2
    import rclpy
    from rclpy.node import Node
    from builtin_interfaces.msg import Time
    from sensor_msgs.msg import CompressedImage, Image
    from std_msgs.msg import Header, String

    rclpy.init(args=argv if argv is not None else sys.argv)

    class TactileNode(Node):
        def __init__(self) -> None:
            super().__init__("tactile")
            models = self.declare_parameter("models", "models").value
            runtime = self.declare_parameter("runtime", "onnx").value
            compressed = self.declare_parameter("compressed", False).value
            video = self.declare_parameter("video", "").value
            self.frame_id = ""
            self.seen = {"lost": 0, "scaled": 0, "keyframes_without_parameters": 0}
            self.logic = PalpationNode(models, runtime)
            self.results = self.create_publisher(String, "~/result", 10)
            self.masks = self.create_publisher(Image, "~/tendon_mask", 10)
            if video:
                if video == "ffmpeg":
                    from ffmpeg_image_transport_msgs.msg import FFMPEGPacket as Video
                elif video == "h264":
                    from h264_msgs.msg import Packet as Video
                elif video == "compressed":
                    Video = CompressedImage
                else:
                    from foxglove_msgs.msg import CompressedVideo as Video
                # Every packet is needed to decode the next: a deep queue.
                self.create_subscription(Video, "image", self.on_video, 30)
            else:
                # A queue of 1: a slow model skips to the newest frame.
                self.create_subscription(CompressedImage if compressed else Image, "image", self.on_image, 1)

        def on_image(self, msg: Any) -> None:
            try:
                self.publish(self.logic.handle(msg), msg.header.frame_id)
            except ValueError as e:
                self.get_logger().warning(f"frame skipped: {e}")

        def on_video(self, msg: Any) -> None:
            try:
                outputs = self.logic.handle_video(msg)
            except ValueError as e:
                self.get_logger().warning(f"packet skipped: {e}")
                return
            self.log_new("keyframes_without_parameters", "keyframe(s) came without their parameter "
                         "sets (SPS, AV1's sequence header), sent before this subscription began: no "
                         "frame until one carries them; have the encoder repeat them at every keyframe "
                         "(x264's repeat-headers=1, GStreamer's h264parse config-interval=-1)")
            self.log_new("lost", "packet(s) gave no frame (damaged); the frames after them "
                         "keep their own stamps")
            self.log_new("scaled", "change(s) of frame size came too often (past 64, sooner than "
                         "one per 32 packets): their frames are scaled to the size before")
            frame_id = msg.frame_id if hasattr(msg, "frame_id") else msg.header.frame_id
            for out in outputs:
                self.publish(out, frame_id)

        def log_new(self, count: str, what: str) -> None:
            """Log the decoder's `count` (keyframes_without_parameters, lost, scaled) when it grew."""
            now = getattr(self.logic.video, count) if self.logic.video else 0
            if now > self.seen[count]:
                self.get_logger().warning(f"{now - self.seen[count]} {what} ({now} in all)")
                self.seen[count] = now

        def publish(self, out: Output, frame_id: str) -> None:
            self.results.publish(String(data=json.dumps(out.record)))
            if out.mask is not None:
                t = out.record["stamp_ns"]
                header = Header(stamp=Time(sec=t // 1_000_000_000, nanosec=t % 1_000_000_000), frame_id=frame_id)
                m = Image(header=header, height=out.mask.shape[0], width=out.mask.shape[1],
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
