"""The package's Fast DDS profile (gyro_instrument/ros/dds_profile.py, fastdds_profile.xml): chosen
only when the user chose none, and read by Fast DDS without an error (issue 37 item 6)."""

import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

from gyro_instrument.ros.dds_profile import CWD_PROFILE, OPT_OUT, PROFILE, PROFILE_VARIABLES, use_package_profile

NS = {"p": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}


def test_the_profile_sets_only_the_writers_heartbeat_period_to_50_ms():
    # The only setting (the XML's comment and docs/ros.md say why): a default data_writer profile whose
    # heartbeat period is 50 ms; nothing that would override the QoS the nodes ask for in code.
    root = ET.parse(PROFILE).getroot()
    writers = root.findall("p:data_writer", NS)
    assert len(writers) == 1 and writers[0].get("is_default_profile") == "true"
    hb = writers[0].find("p:times/p:heartbeatPeriod", NS)
    assert int(hb.find("p:sec", NS).text) == 0 and int(hb.find("p:nanosec", NS).text) == 50_000_000
    leaves = {el.tag.split("}")[1] for el in root.iter() if len(el) == 0}
    assert leaves == {"sec", "nanosec"}, leaves


def test_set_when_the_user_chose_none(tmp_path):
    env = {"PATH": "/usr/bin"}
    assert use_package_profile(env, cwd=str(tmp_path)) == PROFILE
    assert env[PROFILE_VARIABLES[0]] == PROFILE and os.path.isfile(PROFILE)
    assert use_package_profile(env, cwd=str(tmp_path)) is None          # already set: left as it is


@pytest.mark.parametrize("value", ["/etc/my_profile.xml", ""])
def test_a_profile_the_user_chose_wins(tmp_path, value):
    # FASTRTPS_DEFAULT_PROFILES_FILE, even empty (Fast DDS's own defaults), is the user's choice
    env = {PROFILE_VARIABLES[0]: value}
    assert use_package_profile(env, cwd=str(tmp_path)) is None
    assert env == {PROFILE_VARIABLES[0]: value}


def test_fast_dds_3s_variable_alone_is_given_the_name_fast_dds_2_reads(tmp_path):
    # Fast DDS 2.14 (Jazzy) ignores FASTDDS_DEFAULT_PROFILES_FILE: the user's file is copied to the
    # name it reads, and the package's profile is not used
    env = {PROFILE_VARIABLES[1]: "/etc/my_profile.xml"}
    assert use_package_profile(env, cwd=str(tmp_path)) is None
    assert env == {PROFILE_VARIABLES[1]: "/etc/my_profile.xml", PROFILE_VARIABLES[0]: "/etc/my_profile.xml"}


@pytest.mark.parametrize("value", ["0", "off", "False", "no"])
def test_the_package_variable_opts_out(tmp_path, value):
    env = {OPT_OUT: value}
    assert use_package_profile(env, cwd=str(tmp_path)) is None and env == {OPT_OUT: value}
    env = {OPT_OUT: "1"}
    assert use_package_profile(env, cwd=str(tmp_path)) == PROFILE


def test_a_profile_file_in_the_working_directory_wins(tmp_path):
    (tmp_path / CWD_PROFILE).write_text("<profiles/>")
    env = {}
    assert use_package_profile(env, cwd=str(tmp_path)) is None and env == {}


def test_another_rmw_is_left_alone(tmp_path):
    env = {"RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}
    assert use_package_profile(env, cwd=str(tmp_path)) is None
    assert env == {"RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}
    env = {"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"}
    assert use_package_profile(env, cwd=str(tmp_path)) == PROFILE


#: a node that chooses the profile as the package's nodes do (ros/main.py), then starts rclpy
_NODE = ("from gyro_instrument.ros.dds_profile import use_package_profile; use_package_profile(); "
         "import rclpy; from std_msgs.msg import String; rclpy.init(); n = rclpy.create_node('profile_check'); "
         "n.create_publisher(String, 'profile_check', 10); n.destroy_node(); rclpy.shutdown(); print('ok')")


def _fast_dds_output(tmp_path, **env_vars):
    env = {k: v for k, v in os.environ.items() if k not in PROFILE_VARIABLES + (OPT_OUT,)}
    env.update(env_vars)
    r = subprocess.run([sys.executable, "-c", _NODE], capture_output=True, text=True, env=env, timeout=60,
                       cwd=str(tmp_path))
    assert r.returncode == 0 and r.stdout.strip().splitlines()[-1] == "ok", r.stdout + r.stderr  # Fast DDS logs on stdout
    return r.stdout + r.stderr


@pytest.mark.ros
def test_fast_dds_reads_the_profile_without_an_error(tmp_path):
    # Fast DDS prints "XMLPARSER Error" for a profile it cannot read and goes on with its defaults.
    # The package's profile: no error. Negative controls, so that this check can fail: a broken copy
    # named by FASTRTPS_DEFAULT_PROFILES_FILE, and by FASTDDS_DEFAULT_PROFILES_FILE alone (Fast DDS
    # 2.14 reads it only because use_package_profile copies it to the name it reads).
    bad = tmp_path / "bad.xml"
    bad.write_text(open(PROFILE).read().replace("<sec>0</sec>", "<sec>zero</sec>"))
    assert "XMLPARSER" not in _fast_dds_output(tmp_path)
    assert "XMLPARSER" in _fast_dds_output(tmp_path, **{PROFILE_VARIABLES[0]: str(bad)})
    assert "XMLPARSER" in _fast_dds_output(tmp_path, **{PROFILE_VARIABLES[1]: str(bad)})
    assert "XMLPARSER" not in _fast_dds_output(tmp_path, **{OPT_OUT: "0"})     # Fast DDS's defaults, quietly
