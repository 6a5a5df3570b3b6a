"""QoS profiles as a bag stores them (a channel's ``offered_qos_profiles``), without rclpy.

rosbag2 (jazzy) records, per topic, the QoS every publisher of the topic offered, as a YAML list of
profiles with the policies by name (``history: keep_last``, ``reliability: reliable``,
``durability: transient_local``; older bags carry the integer enums of ``rmw_qos_profile_t``). Its
player offers a topic back with the recorded reliability and durability when every recorded
publisher agreed on them (``Rosbag2QoS::adapt_offer_to_recorded_offers``, rosbag2_transport). This
module writes that list (:func:`profiles_yaml`), reads it back normalized (:func:`parse_profiles`)
and derives what the player offers (:func:`replay_offer`).
"""

import yaml

_INF = {"sec": 9223372036, "nsec": 854775807}
_ENUMS = {
    "history": {0: "system_default", 1: "keep_last", 2: "keep_all", 3: "unknown"},
    "reliability": {0: "system_default", 1: "reliable", 2: "best_effort", 3: "unknown", 4: "best_available"},
    "durability": {0: "system_default", 1: "transient_local", 2: "volatile", 3: "unknown", 4: "best_available"},
    "liveliness": {0: "system_default", 1: "automatic", 2: "manual_by_node", 3: "manual_by_topic", 4: "unknown",
                   5: "best_available"},
}


def profile(history="keep_all", depth=0, reliability="reliable", durability="volatile") -> dict:
    """One QoS profile as :func:`parse_profiles` returns it (policies by rosbag2's lower-case names)."""
    return {"history": history, "depth": int(depth), "reliability": reliability, "durability": durability}


def profiles_yaml(profiles) -> str:
    """rosbag2 jazzy's ``offered_qos_profiles`` text (a YAML list, string enums) for ``profiles``
    (dicts as :func:`profile` makes; the deadline, lifespan and lease are infinite, liveliness
    automatic, as rclpy's defaults)."""
    out = []
    for p in profiles:
        out.append({"history": p["history"], "depth": int(p["depth"]), "reliability": p["reliability"],
                    "durability": p["durability"], "deadline": dict(_INF), "lifespan": dict(_INF),
                    "liveliness": "automatic", "liveliness_lease_duration": dict(_INF),
                    "avoid_ros_namespace_conventions": False})
    return yaml.safe_dump(out, sort_keys=False)


def parse_profiles(text) -> list:
    """The profiles of an ``offered_qos_profiles`` text (integer or string enums) as dicts of
    :func:`profile`'s keys; an unreadable text gives the empty list (nothing known)."""
    try:
        items = yaml.safe_load(text or "[]") or []
    except yaml.YAMLError:
        return []
    if not isinstance(items, list):
        return []
    out = []
    for item in items:
        if not isinstance(item, dict):
            continue
        p = {}
        for key in ("history", "reliability", "durability"):
            v = item.get(key)
            p[key] = _ENUMS[key].get(v, "unknown") if isinstance(v, int) else str(v or "unknown").lower()
        p["depth"] = int(item.get("depth") or 0)
        out.append(p)
    return out


def replay_offer(profiles) -> dict:
    """What a player offers for a topic recorded with ``profiles``: reliability and durability as
    recorded when every publisher agreed (``best_effort`` / ``volatile`` otherwise, or when nothing was
    recorded, except that no record at all gives ``reliable``: this package's older bags); ``depth``:
    the largest recorded KEEP_LAST depth (1 when none), which a TRANSIENT_LOCAL topic keeps for late
    subscribers. (History is the player's: see ``msg_docs/topics.md``.)"""
    rel = {p["reliability"] for p in profiles}
    dur = {p["durability"] for p in profiles}
    depths = [p["depth"] for p in profiles if p["history"] == "keep_last" and p["depth"] > 0]
    return {"reliability": "reliable" if not profiles or rel == {"reliable"} else "best_effort",
            "durability": "transient_local" if profiles and dur == {"transient_local"} else "volatile",
            "depth": max(depths, default=1)}
