"""Effects by what they are, never by name (issue 35 item 4).

* A new damping effect (an eddy-current brake, torque −c q̇, defined and registered here only) listed
  on the shipped ``gyrotheodolite`` scene is a term the plane gyroscope's reduced equation does not
  carry, so its run takes the hinge chain; the chain carries the torsion tape (before issue 35 it did
  not: the run equalled the no-tape run to 2.6e-9 rad while the predictions reported the tape).
* A model that cannot carry an effect the scene lists is refused with one line naming the effect, the
  instrument and the model; ``check_effects`` checks the model actually taken.
* Effects read their sizes from an open mapping of scales the instrument fills.
* No effect-name literal outside ``effects/`` and ``scenes/`` (the grep of issue 35 item 4).
* The shipped effects are registered (not: no other effect may exist).
"""

import math
import pathlib
import re

import numpy as np
import pytest

from gyro_instrument import effects
from gyro_instrument.core.effect import (DAMPING, RESTORING_LAW, SPIN, TERM_KINDS, Effect, EffectContext, Scales,
                                         uncarried_terms)
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.params import Param
from gyro_instrument.core.site import Site
from gyro_instrument.instruments import REGISTRY as INSTRUMENTS
from gyro_instrument.scenes import build_instruments, load_scene

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: c of the eddy-current brake, N m s (issue 35's reproduction: listing it at this size dropped the tape)
EDDY_C = 1.0e-12


class EddyCurrent(Effect):
    """An eddy-current brake on a swinging hinge: torque −c q̇ (N m), whatever the hinge's inertia — a
    ``damping`` term of general form (no declared term kind: no hand-derived model carries it)."""

    name = "eddy_current_test"
    summary = "eddy-current brake on the swinging hinges: torque -c q'"
    MECHANICS = frozenset({DAMPING})
    PARAMS = (Param("coefficient_n_m_s", default=EDDY_C, low=0.0, doc="c, N m s"),)

    def relative_size(self, ctx) -> tuple:
        inertia = ctx.scales.get("swing_inertia_kg_m2")
        if not (inertia and ctx.scales.duration_s):
            return 0.0, "no swinging inertia among the instrument's scales"
        return self.p.coefficient_n_m_s * ctx.scales.duration_s / (2.0 * inertia), "c duration / (2 J)"

    def damping_torque(self, ctx, inertia, rate) -> float:
        return -self.p.coefficient_n_m_s * rate


class CubicLaw(Effect):
    """A restoring law of general form (u − u³/6, no declared term kind): no model of the shipped
    instruments carries it."""

    name = "cubic_law_test"
    summary = "restoring law u - u^3/6"
    MECHANICS = frozenset({RESTORING_LAW})

    def relative_size(self, ctx) -> tuple:
        return 0.0, "-"

    def restoring_law(self, ctx):
        return lambda u: u - u ** 3 / 6.0


class BearingDrag(Effect):
    """A spin torque of general form (constant drag −Q sign ρ): not the viscous form the free
    gyroscope's splitting and DOP853 paths carry."""

    name = "bearing_drag_test"
    summary = "constant bearing drag on the rotor"
    MECHANICS = frozenset({SPIN})

    def relative_size(self, ctx) -> tuple:
        return 0.0, "-"

    def spin_torque(self, ctx, inertia, spin_rate) -> float:
        return -1e-9 * math.copysign(1.0, spin_rate)


@pytest.fixture
def registered():
    for cls in (EddyCurrent, CubicLaw, BearingDrag):
        effects.register(cls)
    yield
    for cls in (EddyCurrent, CubicLaw, BearingDrag):
        effects.unregister(cls.name)


#: the rotor-on gyroscope of the gyrotheodolite scene over 600 s (more than one swing of ~460 s)
THEO = ["duration_s=600"]
NO_TAPE = ["effects.tape_torsion=null", "effects.tape_drift=null", "instruments.gak1_rotor_off=null"]
EDDY = [f"effects.eddy_current_test={{coefficient_n_m_s: {EDDY_C:.1e}}}"]


def _gak1(over):
    return build_instruments(load_scene("gyrotheodolite", THEO + over))["gak1"]


def _mean_over_one_swing_period(inst, t0=0.0):
    """The angle's time mean over one full period 2T from ``t0`` (trapezoid on 4001 points), and the
    middle of that period (s): for a linear swing about a centre moving linearly in time, the centre
    at the middle."""
    T = 2.0 * inst.predictions()["swing_duration_s"]
    t = np.linspace(t0, t0 + T, 4001)
    u = inst.simulate(t).columns["angle"]
    return float(np.sum(0.5 * (u[1:] + u[:-1])) / (t.size - 1)), t0 + 0.5 * T


def test_an_uncarried_damping_effect_keeps_the_torsion_tape(registered):
    """Issue 35 reproduced: the eddy current is outside the reduced equation, so the chain runs, and
    the chain carries the tape. (1) The tape moves the swing centre by its predicted amount: the mean
    over one period with the tape less the mean without it equals the exact equilibrium's offset
    c(t) − M at mid-period (:meth:`PlaneGyroscope.equilibrium_reading_rad`, the drift included) to
    2e-3 of it (the sine law's asymmetry about c shifts the mean by ~a²/8 of c's offset from north,
    a = 1°: 4e-5; trapezoid error ~1e-7). Before the fix the with- and without-tape runs agreed to 2.6e-9 rad.
    (2) The run equals the reduced model's run without the eddy current to within c's effect: the
    amplitude it removes, a c t / (2A) ≤ 2.7e-9 rad at 600 s, plus the two models' integration
    difference at rtol 1e-11 (measured 3e-11 rad; allowed 2e-9)."""
    eddy = _gak1(EDDY)
    assert eddy.chosen_integrator()[0] == "vector" and "eddy_current_test" in eddy.chosen_integrator()[1]
    bare = _gak1(EDDY + NO_TAPE)
    with_tape, mid = _mean_over_one_swing_period(eddy)
    without, _ = _mean_over_one_swing_period(bare)
    predicted = eddy.equilibrium_reading_rad(mid) - eddy.mount_reading_rad
    assert abs(predicted) > 1e-5                     # the tape's pull is far above c's effect
    assert (with_tape - without) == pytest.approx(predicted, rel=2e-3)

    reduced = _gak1([])
    assert reduced.chosen_integrator()[0] == "scalar"
    t = np.arange(0.0, 601.0, 1.0)
    u_eddy = eddy.simulate(t)
    u_reduced = reduced.simulate(t)
    assert u_eddy.extra["model"] == "chain" and u_reduced.extra["model"] == "reduced"
    a = abs(eddy.p.initial_angle_rad)
    bound = a * EDDY_C * 600.0 / (2.0 * eddy.p.transverse_inertia_kg_m2) + 2e-9
    assert np.max(np.abs(u_eddy.columns["angle"] - u_reduced.columns["angle"])) < bound


def test_the_chain_carries_every_term_kind_the_reduced_equation_carries():
    """The plane gyroscope's fallback holds all its fast path holds: each term kind of the reduced model
    is carried by the chain, itself or through the kind of mechanics it refines (torsion included)."""
    models = INSTRUMENTS["plane_gyroscope"].MODELS
    assert not {k for k in models["reduced"] if k not in models["chain"] and TERM_KINDS[k] not in models["chain"]}


def test_the_chain_with_the_tape_equals_the_reduced_model_with_it():
    """model: chain with the tape (refused before issue 35) runs the tape too: the shipped scene's
    gyroscope as the chain and as the reduced equation agree over 600 s to 2e-9 rad (the two models'
    integration difference at rtol 1e-11, measured 3e-11 rad)."""
    chain = _gak1(["instruments.gak1.model=chain"])
    reduced = _gak1([])
    t = np.arange(0.0, 601.0, 2.0)
    a, b = chain.simulate(t), reduced.simulate(t)
    assert a.extra["model"] == "chain" and b.extra["model"] == "reduced"
    assert np.max(np.abs(a.columns["angle"] - b.columns["angle"])) < 2e-9


@pytest.mark.parametrize("scene,over,words", [
    ("gyrotheodolite", ["effects.cubic_law_test={}", "instruments.gak1_rotor_off=null"],
     ["instruments.gak1.effects = 'cubic_law_test'", "chain model of plane_gyroscope", "restoring_law",
      "no model of plane_gyroscope carries it"]),
    ("free_gyroscope", ["effects.bearing_drag_test={}"],
     ["effects = 'bearing_drag_test'", "analytic model of free_gyroscope", "spin"]),
    ("free_gyroscope", ["effects.bearing_drag_test={}", "instruments.free_gyro.model=numerical"],
     ["effects = 'bearing_drag_test'", "numerical model of free_gyroscope"]),
    ("free_gyroscope", ["effects.spin_decay={time_constant_s: 600}"],
     ["effects = 'spin_decay'", "analytic model of free_gyroscope", "viscous_spin_friction",
      "the numerical model of free_gyroscope carries it"]),
    ("foucault_pantheon", ["effects.cubic_law_test={}"],
     ["effects = 'cubic_law_test'", "model of spherical_pendulum", "restoring_law"]),
], ids=["plane-law", "free-analytic-drag", "free-numerical-drag", "free-analytic-spin-decay", "pendulum-law"])
def test_a_model_that_cannot_carry_an_effect_is_refused_in_one_line(registered, scene, over, words):
    with pytest.raises(SceneError) as err:
        load_scene(scene, over)
    msg = str(err.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, (w, msg)


def test_every_model_carries_what_it_is_taken_for_in_the_shipped_scenes():
    """check_effects checks the model actually taken: on every shipped scene each instrument's model
    carries each of its effects (a scene that loads runs every term it lists)."""
    from gyro_instrument.scenes import shipped_scene_names
    for name in shipped_scene_names():
        for iname, inst in build_instruments(load_scene(name)).items():
            model = inst.taken_model()
            if model is None:
                continue
            for ename, e in inst.effects.items():
                assert not uncarried_terms(e, inst.MODELS[model], inst.MECHANICS), (name, iname, model, ename)


def test_scales_are_an_open_mapping_an_instrument_fills():
    """A new effect reads a scale no core code names (``swing_inertia_kg_m2`` here): the mapping holds
    what the instrument put in, the common scales have their defaults, a missing one reads as the default
    given to ``get``."""
    s = Scales(7.29e-5, duration_s=10.0, swing_inertia_kg_m2=2.0)
    ctx = EffectContext.of_site(Site.from_degrees(45.0), s)
    assert EddyCurrent(coefficient_n_m_s=0.4).relative_size(ctx)[0] == pytest.approx(0.4 * 10.0 / 4.0)
    assert s.amplitude_rad == 0.0 and s.get("torsion_share", 0.0) == 0.0 and s["swing_inertia_kg_m2"] == 2.0
    with pytest.raises(AttributeError, match="torsion_share"):
        s.torsion_share
    with pytest.raises(TypeError):
        s["duration_s"] = 1.0                            # frozen, as the context holding it


def test_describe_sizes_a_new_effect_from_a_scale_the_instrument_provides(registered):
    """``describe`` shows the eddy current's size c · duration / (2 J) from the plane gyroscope's own scale
    ``swing_inertia_kg_m2`` (J = A = 1.62e-3 kg m² in the gyrotheodolite scene), 600 s: 1.85e-7."""
    from gyro_instrument import api
    out = api.describe(load_scene("gyrotheodolite", THEO + EDDY))
    size = out["instruments"]["gak1"]["effects"]["eddy_current_test"]
    assert size["active"] and size["relative_size"] == pytest.approx(EDDY_C * 600.0 / (2.0 * 1.62e-3), rel=1e-12)


def test_the_shipped_effects_are_registered():
    """Each shipped effect module's class is in the registry under its name, in the summing order;
    any other registered effect may exist beside them (this test does not freeze the set)."""
    shipped = ["earth_rotation", "centrifugal", "finite_amplitude", "ring_inertia", "spin_decay", "pivot_damping",
               "air_drag", "tape_torsion", "tape_drift"]
    names = list(effects.REGISTRY)
    assert [n for n in names if n in shipped] == shipped
    for path in sorted((ROOT / "gyro_instrument" / "effects").glob("*.py")):
        if path.stem != "__init__":
            assert path.stem in effects.REGISTRY, path.stem


#: the grep of issue 35 item 4, in Python: an effect name quoted in a source file outside effects/, scenes/
EFFECT_LITERAL = re.compile(r"[\"'](earth_rotation|centrifugal|finite_amplitude|ring_inertia|spin_decay|pivot_damping"
                            r"|air_drag|tape_torsion|tape_drift)[\"']")


def test_no_effect_name_literal_outside_effects_and_scenes():
    """Instruments declare the kinds of term they sum, the bench builds scenes through the registry:
    no module outside ``gyro_instrument/effects`` and ``gyro_instrument/scenes`` quotes an effect's name."""
    found = []
    for path in sorted((ROOT / "gyro_instrument").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith(("gyro_instrument/effects/", "gyro_instrument/scenes/")):
            continue
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if EFFECT_LITERAL.search(line):
                found.append(f"{rel}:{i}: {line.strip()}")
    assert not found, "effect names quoted outside effects/ and scenes/:\n" + "\n".join(found)


def test_the_literal_check_catches_what_it_looks_for():
    assert EFFECT_LITERAL.search('if self.has("spin_decay"):')
    assert EFFECT_LITERAL.search("x = {'tape_torsion', 'tape_drift'}")
    assert not EFFECT_LITERAL.search("``spin_decay`` in a docstring, effects.tape_torsion.zero_deg")


def test_a_plug_in_effect_the_model_cannot_carry_is_one_line_exit_2(registered, capsys):
    """Bad input (issue 35): the command line prints the refusal on one line and exits 2, no traceback."""
    from gyro_instrument.cli import main
    assert main(["describe", "free_gyroscope", "--set", "effects.bearing_drag_test={}"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bearing_drag_test" in err and "analytic model of free_gyroscope" in err, err


def test_registration_refuses_terms_an_effect_does_not_have():
    """A term kind refining a kind the effect does not declare, an unknown one, or one whose coefficient
    hook is not implemented: refused at registration, the registry unchanged."""
    before = dict(effects.REGISTRY)

    class WrongKind(EddyCurrent):
        name = "wrong_kind_test"
        TERMS = frozenset({"viscous_spin_friction"})        # refines spin, not damping

    class Unknown(EddyCurrent):
        name = "unknown_term_test"
        TERMS = frozenset({"magnetic_something"})

    class NoCoefficient(EddyCurrent):
        name = "no_coefficient_test"
        TERMS = frozenset({"viscous_damping"})              # without viscous_damping_rate_per_s

    for cls, words in ((WrongKind, "not term kinds refining"), (Unknown, "not term kinds refining"),
                       (NoCoefficient, "viscous_damping_rate_per_s")):
        with pytest.raises(ValueError, match=words):
            effects.register(cls)
    assert effects.REGISTRY == before
