"""The package's Fast DDS profile (``fastdds_profile.xml`` beside this module), chosen before
``rclpy.init`` by every node of the package and by ``run`` (issue 37 item 6).

Fast DDS 2.14 (ROS 2 Jazzy's) reads its XML profiles once per process, from the file named by
``FASTRTPS_DEFAULT_PROFILES_FILE``, else from ``DEFAULT_FASTRTPS_PROFILES.xml`` in the working
directory; it ignores ``FASTDDS_DEFAULT_PROFILES_FILE`` (Fast DDS 3's name). :func:`use_package_profile`
points ``FASTRTPS_DEFAULT_PROFILES_FILE`` at the package's file only when the user chose no profile
and the RMW is Fast DDS, so a user's own profile always wins: a ``FASTDDS_DEFAULT_PROFILES_FILE``
alone is copied to ``FASTRTPS_DEFAULT_PROFILES_FILE`` so that Fast DDS 2.14 reads it too.
``GYRO_INSTRUMENT_FASTDDS_PROFILE=0`` runs on Fast DDS's own defaults (an empty
``FASTRTPS_DEFAULT_PROFILES_FILE`` does too, but Fast DDS then logs a harmless ``XMLPARSER Error``
line in every process).

The profile sets one timing: reliable writers' heartbeat period, 50 ms instead of 3 s (the XML
file says why). Measured on quet_paris, 600 s at real-time factor 0 with recording, separate nodes
(docs/ros.md, "The package's Fast DDS profile").
"""

import os

#: the package's profile file
PROFILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fastdds_profile.xml")
#: the environment variables naming a profile file: Fast DDS 2.x's (read by Jazzy's 2.14) and 3.x's
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")
#: set to 0 (or off, false, no) to run on Fast DDS's own defaults
OPT_OUT = "GYRO_INSTRUMENT_FASTDDS_PROFILE"
#: the file Fast DDS loads from the working directory when no variable is set
CWD_PROFILE = "DEFAULT_FASTRTPS_PROFILES.xml"
#: RMW implementations that read Fast DDS profiles (unset: rclpy's default, rmw_fastrtps_cpp)
FAST_DDS_RMWS = ("", "rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp")


def use_package_profile(environ=os.environ, cwd=None) -> str | None:
    """Set ``FASTRTPS_DEFAULT_PROFILES_FILE`` in ``environ`` to :data:`PROFILE` unless the user chose
    otherwise: :data:`OPT_OUT` set to 0, either variable of :data:`PROFILE_VARIABLES` set (even
    empty; ``FASTDDS_DEFAULT_PROFILES_FILE`` alone is copied to ``FASTRTPS_DEFAULT_PROFILES_FILE``,
    the one Fast DDS 2.14 reads), :data:`CWD_PROFILE` in ``cwd``, or an RMW that is not Fast DDS
    (``RMW_IMPLEMENTATION``); nor when the file is missing. Call before ``rclpy.init``.

    Returns
    -------
    str or None
        The package's profile file when it was set, else None.
    """
    if environ.get(OPT_OUT, "").strip().lower() in ("0", "off", "false", "no"):
        return None
    first, second = PROFILE_VARIABLES
    if first in environ:
        return None
    if second in environ:
        environ[first] = environ[second]          # the user's file, under the name Fast DDS 2.14 reads
        return None
    if environ.get("RMW_IMPLEMENTATION", "") not in FAST_DDS_RMWS:
        return None
    if os.path.exists(os.path.join(cwd or os.getcwd(), CWD_PROFILE)) or not os.path.exists(PROFILE):
        return None
    environ[first] = PROFILE
    return PROFILE


__all__ = ["CWD_PROFILE", "FAST_DDS_RMWS", "OPT_OUT", "PROFILE", "PROFILE_VARIABLES", "use_package_profile"]
