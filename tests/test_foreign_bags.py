"""Bags recorded by other tools (issue 15 part 2): written here by rosbags' rosbag2 Writer (not by
this package's writer), with the scene given as ``replay BAG --scene SCENE``; the instruments'
topics are found by the documented names and types (msg_docs/topics.md), remapped with
``--topic``, and what could not be matched is reported."""

import json

import numpy as np
import pytest

from gyro_instrument.cli import main as core_main, to_jsonable
from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.recording.joints import joint_streams
from gyro_instrument.scenes import load_scene

OVER = ["duration_s=120"]


@pytest.fixture(scope="module")
def streams():
    """quet_paris for 120 s through its sensors: the joint arrays and the core's estimate of the
    same samples (what replay must give)."""
    scene = load_scene("quet_paris", OVER)
    truth = simulate_truth(scene)
    t_ns, st = joint_streams(scene, truth=truth)
    core = to_jsonable(estimate_records(scene, truth[1], measure(scene, truth)))
    return t_ns, st, core


def write_foreign(path, streams, layout=None, extra=True, bare_names=()):
    """A bag written with rosbags' Writer (rosbag2 directory, MCAP storage, typestore ROS2_JAZZY).

    ``layout``: instrument -> topic (default ``/<instrument>/joint_states``); an instrument mapped
    to ``("/topic", "std_msgs/msg/Float64")`` is written as that type instead. ``bare_names``:
    instruments whose joints are written without the ``<instrument>/`` prefix, in reverse order.
    ``extra``: add unrelated topics (a String and an Imu)."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_JAZZY)
    JointState, Header, Time = (ts.types[n] for n in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header",
                                                        "builtin_interfaces/msg/Time"))
    Float64, String = ts.types["std_msgs/msg/Float64"], ts.types["std_msgs/msg/String"]
    t_ns, st, _ = streams
    layout = layout or {}
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {}
        for name in st:
            spec = layout.get(name, f"/{name}/joint_states")
            topic, msgtype = (spec, "sensor_msgs/msg/JointState") if isinstance(spec, str) else spec
            conns[name] = (w.add_connection(topic, msgtype, typestore=ts), msgtype)
        if extra:
            chat = w.add_connection("/chatter", "std_msgs/msg/String", typestore=ts)
            temp = w.add_connection("/lab/temperature", "std_msgs/msg/Float64", typestore=ts)
        for i, t in enumerate(t_ns):
            stamp = EPOCH_NS + int(t)
            hdr = Header(stamp=Time(sec=stamp // 10 ** 9, nanosec=stamp % 10 ** 9), frame_id="")
            for name, s in st.items():
                conn, msgtype = conns[name]
                if msgtype == "std_msgs/msg/Float64":
                    data = ts.serialize_cdr(Float64(data=float(s.position[i, 0])), msgtype)
                else:
                    names, pos, vel = list(s.names), s.position[i], s.velocity[i]
                    eff = s.effort[i]
                    if name in bare_names:
                        names = [n.split("/", 1)[1] for n in names][::-1]
                        pos, vel, eff = pos[::-1], vel[::-1], eff[::-1]
                    data = ts.serialize_cdr(JointState(header=hdr, name=names, position=np.array(pos),
                                                       velocity=np.array(vel), effort=np.array(eff)), msgtype)
                w.write(conn, stamp, data)
            if extra and i % 20 == 0:
                w.write(chat, stamp, ts.serialize_cdr(String(data=f"tick {i}"), "std_msgs/msg/String"))
                w.write(temp, stamp, ts.serialize_cdr(Float64(data=21.5), "std_msgs/msg/Float64"))
    return path


def _replay(capsys, *argv):
    code = core_main(["replay", *argv, "--json"])
    captured = capsys.readouterr()
    return code, (json.loads(captured.out) if code == 0 else captured.err)


def test_foreign_bag_with_extra_topics_replays_to_the_core_estimate(tmp_path, capsys, streams):
    bag = write_foreign(tmp_path / "lab", streams)
    # without a scene: refused, and told how to give it
    code, err = _replay(capsys, str(bag))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--scene SCENE" in err
    code, r = _replay(capsys, str(bag), "--scene", "quet_paris", "--set", "duration_s=120")
    assert code == 0
    topics = r.pop("topics")
    assert topics["matched"] == {n: f"/{n}/joint_states" for n in ("gyro_horizontal", "gyro_meridian", "pendulum")}
    assert topics["unmatched"] == {}
    assert topics["unused"] == {"/chatter": "std_msgs/msg/String", "/lab/temperature": "std_msgs/msg/Float64"}
    notes = r.pop("replay_notes")
    assert any("topics not used: /chatter, /lab/temperature" in n for n in notes)
    # the same samples through another tool's writer: the core's estimate, to the last digit
    assert json.dumps(r, sort_keys=True) == json.dumps(streams[2], sort_keys=True)


def test_right_name_wrong_type_is_reported_and_the_rest_estimated(tmp_path, capsys, streams):
    bag = write_foreign(tmp_path / "typo", streams,
                        layout={"gyro_meridian": ("/gyro_meridian/joint_states", "std_msgs/msg/Float64")})
    code, r = _replay(capsys, str(bag), "--scene", "quet_paris", "--set", "duration_s=120")
    assert code == 0
    why = r["topics"]["unmatched"]["gyro_meridian"]
    assert "has type std_msgs/msg/Float64, expected sensor_msgs/msg/JointState" in why
    assert set(r["topics"]["matched"]) == {"gyro_horizontal", "pendulum"}
    assert "gyro_meridian" not in r["instruments"]
    # what the core estimates from the same two instruments' samples
    scene = load_scene("quet_paris", OVER)
    truth = simulate_truth(scene)
    both = {n: truth[1][n] for n in ("gyro_horizontal", "pendulum")}
    expected = to_jsonable(estimate_records(scene, both, measure(scene, truth)))
    assert json.dumps({k: v for k, v in r.items() if k not in ("topics", "replay_notes")}, sort_keys=True) == \
        json.dumps(expected, sort_keys=True)
    assert any(n.startswith("gyro_meridian not matched") for n in r["replay_notes"])
    # text output says it too
    assert core_main(["replay", str(bag), "--scene", "quet_paris", "--set", "duration_s=120"]) == 0
    assert "note: gyro_meridian not matched: topic /gyro_meridian/joint_states has type" in capsys.readouterr().out


def test_remapped_topic_with_bare_joint_names(tmp_path, capsys, streams):
    bag = write_foreign(tmp_path / "remap", streams, layout={"pendulum": "/lab/bob/joints"},
                        bare_names=("pendulum",), extra=False)
    code, r = _replay(capsys, str(bag), "--scene", "quet_paris", "--set", "duration_s=120")
    assert code == 0 and "no topic /pendulum/joint_states" in r["topics"]["unmatched"]["pendulum"]
    assert r["topics"]["unused"] == {"/lab/bob/joints": "sensor_msgs/msg/JointState"}
    code, r = _replay(capsys, str(bag), "--scene", "quet_paris", "--set", "duration_s=120",
                      "--topic", "pendulum=/lab/bob/joints")
    assert code == 0 and r["topics"]["matched"]["pendulum"] == "/lab/bob/joints"
    r.pop("topics")
    r.pop("replay_notes", None)
    assert json.dumps(r, sort_keys=True) == json.dumps(streams[2], sort_keys=True)


@pytest.mark.parametrize("case", ["nothing matches", "bad --topic", "unknown instrument", "wrong joints"])
def test_foreign_bag_bad_input_exits_2_with_one_line(tmp_path, capsys, streams, case):
    argv = ["--scene", "quet_paris", "--set", "duration_s=120"]
    if case == "nothing matches":
        bag = write_foreign(tmp_path / "b", streams, extra=True, layout={n: f"/other/{n}" for n in streams[1]})
        expect = "does not match the scene quet_paris: gyro_horizontal: no topic /gyro_horizontal/joint_states"
    elif case == "wrong joints":
        # the pendulum's joints published as a gyroscope's topic, and nothing else
        t_ns, st, core = streams
        bag = write_foreign(tmp_path / "b", (t_ns, {"gyro_horizontal": st["pendulum"]}, core), extra=False)
        argv = ["--scene", "quet_paris", "--set", "duration_s=120", "--set", "instruments.pendulum=null",
                "--set", "instruments.gyro_meridian=null"]
        expect = "lacks the joints axis, rotor of a plane_gyroscope (its joints: pendulum/deflection_east"
    else:
        bag = write_foreign(tmp_path / "b", streams, extra=False)
        argv += ["--topic", "pendulum:/x" if case == "bad --topic" else "bob=/x"]
        expect = "must be INSTRUMENT=/topic" if case == "bad --topic" else "names no instrument of the scene"
    code, err = _replay(capsys, str(bag), *argv)
    assert code == 2 and len(err.strip().splitlines()) == 1 and expect in err, err
