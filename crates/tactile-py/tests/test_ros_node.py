"""The example ROS 2 node's logic, without ROS: it imports nothing of ROS,
converts every image encoding it names as `tactile run` does on a bag, and
gives the pipeline's answer with the header's stamp."""

from __future__ import annotations

import importlib.util
import sys
from types import SimpleNamespace

import numpy as np
import pytest

import tactile


@pytest.fixture(scope="module")
def node_module(root):
    path = root / "examples" / "ros2" / "tactile_node.py"
    spec = importlib.util.spec_from_file_location("tactile_node", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["tactile_node"] = module
    spec.loader.exec_module(module)
    assert "rclpy" not in sys.modules
    return module


def image_msg(data: np.ndarray, encoding: str, step: int, bigendian: int = 0, width: int | None = None):
    h, w = data.shape[0], width or data.shape[1]
    return SimpleNamespace(
        header=SimpleNamespace(stamp=SimpleNamespace(sec=1_700_000_000, nanosec=42), frame_id="cam"),
        height=h, width=w, encoding=encoding, is_bigendian=bigendian, step=step, data=data.tobytes(),
    )


def test_node_converts_each_encoding(node_module, root, palpation_frames):
    rgb = palpation_frames[4]
    h, w, _ = rgb.shape
    grey = rgb[:, :, 1]
    cases = [
        (image_msg(rgb, "rgb8", w * 3), rgb),
        (image_msg(np.ascontiguousarray(rgb[:, :, ::-1]), "bgr8", w * 3), rgb),
        # cv_bridge's cv2_to_imgmsg of an OpenCV (BGR) frame without an encoding.
        (image_msg(np.ascontiguousarray(rgb[:, :, ::-1]), "8UC3", w * 3), rgb),
        (image_msg(np.dstack([rgb, np.full((h, w), 255, np.uint8)]), "rgba8", w * 4), rgb),
        (image_msg(np.pad(grey, ((0, 0), (0, 8))), "mono8", w + 8, width=w), np.repeat(grey[:, :, None], 3, 2)),
        (image_msg(grey.astype(">u2") * 257, "mono16", w * 2, 1), np.repeat(grey[:, :, None], 3, 2)),
    ]
    for msg, want in cases:
        np.testing.assert_array_equal(node_module.image_to_rgb(msg), want, err_msg=msg.encoding)
    # A CompressedImage (image_transport's compressed transport): PNG
    # exactly, JPEG within its loss.
    png = sorted((root / "samples" / "palpation").glob("*.png"))[5].read_bytes()
    compressed = SimpleNamespace(header=image_msg(rgb, "rgb8", w * 3).header, format="rgb8; png compressed rgb8",
                                 data=np.frombuffer(png, np.uint8))
    np.testing.assert_array_equal(node_module.image_to_rgb(compressed), palpation_frames[5])
    with pytest.raises(ValueError, match=r"not a picture in a format frames are read in"):
        node_module.image_to_rgb(SimpleNamespace(format="jpeg", data=b"not a picture"))
    with pytest.raises(ValueError, match=r"not a sensor_msgs/msg/CompressedImage: it has no field \"data\""):
        node_module.image_to_rgb(SimpleNamespace(format="jpeg"))
    with pytest.raises(ValueError, match=r"encoding \"nv21\" is not one of rgb8, bgr8"):
        node_module.image_to_rgb(image_msg(rgb, "nv21", w * 3))
    with pytest.raises(ValueError, match=r"no field \"step\""):
        node_module.image_to_rgb(SimpleNamespace(height=h, width=w, encoding="rgb8", is_bigendian=0, data=b""))
    with pytest.raises(ValueError, match=r"field \"height\": must be an integer"):
        node_module.image_to_rgb(SimpleNamespace(**{**vars(image_msg(rgb, "rgb8", w * 3)), "height": -1}))
    with pytest.raises(ValueError, match="needs"):
        node_module.image_to_rgb(SimpleNamespace(**{**vars(image_msg(rgb, "rgb8", w * 3)), "height": h + 1}))


def test_an_int_given_as_a_message_s_data_is_refused():
    """bytes(n) is n zero bytes: an int slipped in as `data` (a length, a
    handle) was read as a black picture or an empty packet."""
    one_pixel = SimpleNamespace(height=1, width=1, encoding="mono8", is_bigendian=0, step=1, data=1)
    with pytest.raises(ValueError, match=r'^sensor_msgs/msg/Image field "data": not bytes \(an int, 1: bytes\(\) would make'):
        tactile.ros_image_to_rgb(one_pixel)
    with pytest.raises(ValueError, match=r"^a packet's data: not bytes \(an int, 5: "):
        tactile.VideoDecoder("h264").decode(5)
    # What rclpy and numpy give stays read.
    import array
    for data in (b"\x07", bytearray(b"\x07"), array.array("B", [7]), np.array([7], np.uint8)):
        assert tactile.ros_image_to_rgb(SimpleNamespace(**{**vars(one_pixel), "data": data})).tolist() == [[[7, 7, 7]]]


def test_node_answers_as_the_pipeline(node_module, root, palpation_frames):
    node = node_module.PalpationNode(str(root / "models"), "onnx")
    direct = tactile.Pipeline(root / "models", "onnx")
    for rgb in palpation_frames:
        h, w, _ = rgb.shape
        out = node.handle(image_msg(np.ascontiguousarray(rgb[:, :, ::-1]), "bgr8", w * 3))
        want = direct.process(rgb)
        assert out.record["tendon"] == want.tendon
        assert out.record["score"] == pytest.approx(want.score)
        assert out.record["stamp_ns"] == 1_700_000_000_000_000_042
        if want.tendon:
            assert out.mask.shape == (h, w) and int((out.mask == 255).sum()) == int(want.mask.sum())
        else:
            assert out.mask is None


def test_node_answers_a_video_topic_frame_by_frame(node_module, root, palpation_frames, tmp_path):
    """CompressedVideo messages (lossless H.264, one frame each) as rclpy
    gives them, and the same packets as h264_msgs Packets and as
    CompressedImages of format h264: each message's own frame answered as
    the pipeline answers the PNG, stamped with the message's timestamp."""
    import array

    from test_robots import lossless_h264_packets

    packets = lossless_h264_packets(root / "samples" / "palpation", tmp_path)
    node = node_module.PalpationNode(str(root / "models"), "onnx")
    h264_node = node_module.PalpationNode(str(root / "models"), "onnx")
    image_node = node_module.PalpationNode(str(root / "models"), "onnx")
    direct = tactile.Pipeline(root / "models", "onnx")
    for i, (data, rgb) in enumerate(zip(packets, palpation_frames)):
        msg = SimpleNamespace(timestamp=SimpleNamespace(sec=1_700_000_000 + i, nanosec=7), frame_id="cam",
                              data=array.array("B", data), format="h264")
        outs = node.handle_video(msg)
        assert len(outs) == 1, i
        # The same packet as h264_image_transport's Packet (header, seq).
        packet = SimpleNamespace(header=SimpleNamespace(stamp=msg.timestamp, frame_id="cam"), seq=i, data=data)
        assert [o.record["score"] for o in h264_node.handle_video(packet)] == [outs[0].record["score"]], i
        # As GStreamer's ROS 2 sink publishes it: a CompressedImage (header, format).
        image = SimpleNamespace(header=packet.header, format="h264", data=data)
        assert [o.record["score"] for o in image_node.handle_video(image)] == [outs[0].record["score"]], i
        want = direct.process(rgb)
        assert outs[0].record["tendon"] == want.tendon
        assert outs[0].record["score"] == pytest.approx(want.score)
        assert outs[0].record["stamp_ns"] == (1_700_000_000 + i) * 1_000_000_000 + 7
