"""The package's Fast DDS profile (``fastdds_profile.xml`` beside this module), chosen before
``rclpy.init`` by every node of the package and by ``run`` (issue 37 item 6).

Fast DDS reads its XML profiles once per process, from the file named by
``FASTRTPS_DEFAULT_PROFILES_FILE`` (or ``FASTDDS_DEFAULT_PROFILES_FILE``), else from
``DEFAULT_FASTRTPS_PROFILES.xml`` in the working directory. :func:`use_package_profile` points
``FASTRTPS_DEFAULT_PROFILES_FILE`` at the package's file only when none of these is set and the RMW
is Fast DDS, so a user's own profile (or an empty value: Fast DDS's defaults) always wins.

The profile sets one timing: reliable writers' heartbeat period, 50 ms instead of 3 s (the XML
file says why). Measured on quet_paris, 600 s at real-time factor 0 with recording, separate nodes
(docs/ros.md, "Parameters, services and the route's speed").
"""

import os

#: the package's profile file
PROFILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fastdds_profile.xml")
#: the environment variables Fast DDS reads its profile file from (2.x name first)
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")
#: the file Fast DDS loads from the working directory when no variable is set
CWD_PROFILE = "DEFAULT_FASTRTPS_PROFILES.xml"
#: RMW implementations that read Fast DDS profiles (unset: rclpy's default, rmw_fastrtps_cpp)
FAST_DDS_RMWS = ("", "rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp")


def use_package_profile(environ=os.environ, cwd=None) -> str | None:
    """Set ``FASTRTPS_DEFAULT_PROFILES_FILE`` in ``environ`` to :data:`PROFILE` unless the user chose
    a profile (either variable set, even empty, or :data:`CWD_PROFILE` in ``cwd``), the RMW is not
    Fast DDS (``RMW_IMPLEMENTATION``) or the file is missing. Call before ``rclpy.init``.

    Returns
    -------
    str or None
        The profile file set, or None when nothing was changed.
    """
    if any(var in environ for var in PROFILE_VARIABLES):
        return None
    if environ.get("RMW_IMPLEMENTATION", "") not in FAST_DDS_RMWS:
        return None
    if os.path.exists(os.path.join(cwd or os.getcwd(), CWD_PROFILE)) or not os.path.exists(PROFILE):
        return None
    environ[PROFILE_VARIABLES[0]] = PROFILE
    return PROFILE


__all__ = ["CWD_PROFILE", "FAST_DDS_RMWS", "PROFILE", "PROFILE_VARIABLES", "use_package_profile"]
