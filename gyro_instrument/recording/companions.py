"""A bag's companion records: refuse one that lacks the joint states a record is read beside (a
rotor-off swing), for the replay of this package's bags (:mod:`.replay`) and of foreign ones
(:mod:`.foreign`)."""

from gyro_instrument.core.errors import SceneError


def check_companions(insts, samples, path, remaps=None) -> None:
    """Refuse a bag that lacks the joint states of a record the estimator reads beside an instrument's
    own (:func:`~gyro_instrument.estimators.pipeline.missing_companions`: a rotor-off swing).

    ``remaps``: instrument -> topic (``--topic``) where a foreign bag was read.

    Raises
    ------
    SceneError
        On ``bag``: naming the instrument, its companion and the topic looked for.
    """
    from gyro_instrument.estimators.pipeline import missing_companions
    from gyro_instrument.recording.topics import joint_topic
    for name, key, other in missing_companions(insts, samples):
        topic = (remaps or {}).get(other, "/" + joint_topic(other))
        raise SceneError("bag", path, f"holds no joint states of {other} ({topic}, at least 3 "
                                      f"messages): {name} reads its {key.replace('_', '-')} swing from it")
