"""Effects contribute terms, instruments sum them (issue 12 part 2), and the hand-derived fast paths
are held to the summed terms for every combination of the effects they support.

* The plane gyroscope's scalar right-hand side (Quet sec. 4 §1 eqs. 2–3 with the dropped O(n²) term,
  spin decay and pivot damping written out by hand) against the generic hinge chain, which sums the
  effects' ``rigid_body``, ``damping`` and ``spin`` terms — all 2⁵ subsets of its five effects.
* The pendulum's parareal fast path (first guesses from Quet's comparison pendulum) against the
  adaptive integration of the summed point-mass terms, for every effect set it accepts.
* The effects' component-form terms against their vector helpers (Quet sec. 1 eqs. 16, 19).
"""

import itertools
import math

import numpy as np
import pytest

from gyro_instrument.core.effect import MECHANICS, POINT_MASS, Effect, EffectContext
from gyro_instrument.core.site import Site
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.effects.centrifugal import centrifugal_gradient_acceleration
from gyro_instrument.effects.earth_rotation import coriolis_acceleration
from gyro_instrument.instruments import REGISTRY as INSTRUMENTS
from gyro_instrument.scenes import build_instruments, load_scene

PLANE_EFFECTS = ("earth_rotation", "centrifugal", "finite_amplitude", "spin_decay", "pivot_damping")
EFFECT_PARAMS = {"spin_decay": "{time_constant_s: 100.0}", "pivot_damping": "{time_constant_s: 200.0}"}


def _gyroscopes(effects):
    """quet_paris's two plane gyroscopes (horizontal, meridian) with exactly ``effects``."""
    over = ["effects=null", "instruments.pendulum=null"] + [f"effects.{e}={EFFECT_PARAMS.get(e, '{}')}"
                                                             for e in effects]
    if not effects:
        over = ["effects=null", "instruments.pendulum=null"]
    insts = build_instruments(load_scene("quet_paris", over))
    return [insts["gyro_horizontal"], insts["gyro_meridian"]]


STATES = [(0.1, 0.05, 628.3), (1.0, -0.3, 628.3), (-2.5, 0.2, 50.0), (3.0, 0.0, -300.0)]


@pytest.mark.parametrize("effects", [c for r in range(6) for c in itertools.combinations(PLANE_EFFECTS, r)],
                         ids=lambda c: "+".join(c) or "none")
def test_plane_gyroscope_scalar_path_equals_the_summed_terms(effects):
    """ü and ρ̇ of the hand-derived scalar path equal the hinge chain's (the summed effect terms)
    to rounding. Without ``finite_amplitude`` the scalar path uses the small-angle law u for sin u in
    the restoring torque only: the chain's torque at u̇ = 0 is scaled by u / sin u (the restoring
    law's contribution), its u̇-dependent rest (damping) kept. Tolerance: 1e-12 of the largest term
    (aρ + |b|) — the chain's 3x3 rotations and linear solve round at ~1e-15 relative."""
    for inst in _gyroscopes(effects):
        fast = inst.reduced_rhs_scalar()
        chain = inst.build_chain()
        for u, ud, rho in STATES:
            _, udd, rhod = fast(0.0, u, ud, rho)
            full = chain.rhs(0.0, np.array([u, 0.0, ud, rho]))
            still = chain.rhs(0.0, np.array([u, 0.0, 0.0, rho]))
            udd_ref, rhod_ref = full[2], full[3]
            if "finite_amplitude" not in effects:
                udd_ref = still[2] * u / math.sin(u) + (full[2] - still[2])
            p = inst.site.earth_rate_rad_s * inst.sin_omega
            scale = max(inst.p.inertia_ratio * p * abs(rho) + abs(ud) + abs(rho) / 100.0, 1e-30)
            assert udd == pytest.approx(udd_ref, abs=1e-12 * scale), (inst.name, u, ud, rho)
            assert rhod == pytest.approx(rhod_ref, abs=1e-12 * scale), (inst.name, u, ud, rho)


@pytest.mark.parametrize("effects", [("finite_amplitude",), ("finite_amplitude", "earth_rotation"),
                                     ("finite_amplitude", "centrifugal"),
                                     ("finite_amplitude", "earth_rotation", "centrifugal")],
                         ids=lambda c: "+".join(c))
def test_parareal_fast_path_equals_the_summed_terms(effects):
    """Every effect set the parareal path accepts (finite_amplitude, no air_drag): its bob positions
    over 4 swings match DOP853 on the summed point-mass terms (rtol 1e-11) to 1e-7 of the amplitude
    (shooting_tol 1e-9 per swing, RK8 at 48 steps per period: ~1e-9 measured; margin for rounding)."""
    over = ["duration_s=66", "sample_rate_hz=2", "effects=null"] + [f"effects.{e}={{}}" for e in effects]
    fast = build_instruments(load_scene("foucault_pantheon", over + ["instruments.pendulum.integrator=parareal"]))
    slow = build_instruments(load_scene("foucault_pantheon", over))
    t = np.arange(0.0, 66.0, 0.5)
    a, b = fast["pendulum"].simulate(t), slow["pendulum"].simulate(t)
    amp = 67.0 * math.sin(math.radians(2.0))
    for c in ("x_east", "y_north"):
        assert np.max(np.abs(a.columns[c] - b.columns[c])) < 1e-7 * amp


def test_point_mass_terms_equal_the_vector_helpers():
    """Component-form terms equal −2 Ω × v and −Ω × (Ω × δr) (Quet sec. 1 eqs. 16, 19) to rounding."""
    ctx = EffectContext.of_site(Site.from_degrees(48.8462))
    om = ctx.site.earth_rate_enu()
    rng = np.random.default_rng(3)
    cor = EFFECTS["earth_rotation"]().point_mass_term(ctx)
    cen = EFFECTS["centrifugal"]().point_mass_term(ctx)
    for _ in range(5):
        dr, v = rng.normal(size=3) * 5.0, rng.normal(size=3)
        np.testing.assert_allclose(cor(*dr, *v), coriolis_acceleration(om, v), rtol=0, atol=1e-19)
        np.testing.assert_allclose(cen(*dr, *v), centrifugal_gradient_acceleration(om, dr), rtol=0, atol=1e-21)


def test_spin_and_damping_terms():
    """spin_decay's bearing torque is C times its angular deceleration −ρ/τ; pivot damping −(2/τ) J q̇."""
    sd = EFFECTS["spin_decay"](time_constant_s=50.0)
    ctx = EffectContext.of_site(Site.from_degrees(48.8462))
    assert sd.spin_torque(ctx, 2.0, 600.0) == pytest.approx(2.0 * sd.spin_torque_per_inertia(600.0), rel=1e-15)
    assert EFFECTS["pivot_damping"](time_constant_s=10.0).damping_torque(ctx, 3.0, 0.5) == pytest.approx(-0.3)


def test_every_effect_declares_known_kinds_and_implements_their_hooks():
    """An effect's MECHANICS name known kinds; each declared kind's hook is overridden (the base
    hook contributes nothing); each instrument supports exactly the effects meeting its kinds."""
    hooks = {"point_mass": "point_mass_term", "rigid_body": "rigid_body_torque", "damping": "damping_torque",
             "spin": "spin_torque", "restoring_law": "restoring_law", "carrier_inertia": "carrier_inertia",
             "frame_rate": "frame_rate_rad_s", "torsion": "torsion_term"}
    assert set(hooks) == MECHANICS
    for name, cls in EFFECTS.items():
        assert cls.MECHANICS and cls.MECHANICS <= MECHANICS, name
        for kind in cls.MECHANICS:
            assert getattr(cls, hooks[kind]) is not getattr(Effect, hooks[kind]), (name, kind)
    for tname, cls in INSTRUMENTS.items():
        assert cls.SUPPORTED_EFFECTS == {e for e, ec in EFFECTS.items() if ec.MECHANICS & cls.MECHANICS}


#: a shipped scene holding each instrument type (its effects are replaced in the test below)
SCENE_OF_TYPE = {"plane_gyroscope": "quet_gyroscopes", "spherical_pendulum": "foucault_pantheon",
                 "free_gyroscope": "free_gyroscope", "puiseux_body": "puiseux_spheroid",
                 "gimbal_gyroscope": "gimbal_paris"}


def _users(effect_cls):
    """Instrument types whose declared kinds meet the effect's (derived from MECHANICS alone)."""
    return sorted(t for t, c in INSTRUMENTS.items() if effect_cls.MECHANICS & c.MECHANICS)


@pytest.mark.parametrize("effect", sorted(EFFECTS))
def test_supported_effects_follow_the_declared_mechanics(effect):
    """Derived, not frozen (a new effect needs no edit here; what each instrument supports is recorded
    in the generated msg_docs/instruments.md, whose staleness tests/test_docs.py checks): every registered
    effect reaches some instrument through its MECHANICS, every kind an instrument declares is one some
    effect contributes to, and a scene accepts the effect on an instrument whose kinds it meets and
    refuses it — naming exactly the derived instruments — on one whose kinds it does not. Fails when an
    effect or an instrument is registered with kinds the other side does not have (a typo, a kind
    dropped), or the scene check disagrees with the declarations."""
    from gyro_instrument.core.errors import SceneError
    cls = EFFECTS[effect]
    users = _users(cls)
    assert users, f"{effect}: its kinds {sorted(cls.MECHANICS)} are summed by no instrument"
    for tname, icls in INSTRUMENTS.items():
        assert icls.MECHANICS <= {k for ec in EFFECTS.values() for k in ec.MECHANICS}, tname
    assert set(SCENE_OF_TYPE) <= set(INSTRUMENTS)
    setting = f"effects.{effect}={EFFECT_PARAMS.get(effect, '{}')}"
    for tname, scene in SCENE_OF_TYPE.items():
        over = ["effects=null", setting]
        if tname in users:
            try:
                load_scene(scene, over)
            except SceneError as exc:
                # a type may take an effect in some configurations only (check_effects: a torsion tape
                # hangs a horizontal gyroscope, not quet_gyroscopes' meridian one): refused for the
                # configuration, never as unsupported
                assert "instruments that support it" not in str(exc), exc
        else:
            with pytest.raises(SceneError, match="instruments that support it: " + ", ".join(users)):
                load_scene(scene, over)


def test_terms_are_summed_in_registry_order_whatever_the_scene_order():
    """Floating-point sums depend on order: the instrument sums in the registry's order, so listing
    the effects in another order gives bit-identical results."""
    a = build_instruments(load_scene("foucault_pantheon", ["duration_s=20"]))["pendulum"]
    b = build_instruments(load_scene("foucault_pantheon", [
        "duration_s=20", "effects=null", "effects.finite_amplitude={}", "effects.centrifugal={}",
        "effects.earth_rotation={}"]))["pendulum"]
    assert list(a.effects) == list(b.effects) == ["earth_rotation", "centrifugal", "finite_amplitude"]
    t = np.linspace(0.0, 20.0, 41)
    np.testing.assert_array_equal(a.simulate(t).columns["x_east"], b.simulate(t).columns["x_east"])
    assert POINT_MASS in EFFECTS["earth_rotation"].MECHANICS


def test_a_new_conservative_point_mass_effect_keeps_the_pendulum_fast_path():
    """The pendulum chooses parareal from capabilities, not names (issue 23): an effect registered
    later that declares ``conservative`` keeps ``integrator: auto`` on parareal and its term is
    summed (here g(γ)'s latitude variation read from the context, zero at the site itself: the
    result equals the run without it bit for bit); one that does not declare it drops to adaptive
    with its name in the reason."""
    from gyro_instrument.core.effect import CONSERVATIVE
    from gyro_instrument.effects import register, unregister

    class GravityVariation(Effect):
        name = "gravity_variation_test"
        summary = "test: the change of g over the bob's displacement, from the context's site"
        MECHANICS = frozenset({POINT_MASS})
        CAPABILITIES = frozenset({CONSERVATIVE})
        calls = []

        def relative_size(self, ctx):
            return 0.0, "0 (test)"

        def point_mass_term(self, ctx):
            GravityVariation.calls.append(ctx.gravity_m_s2)
            g0 = ctx.site.gravity_m_s2           # the rest point's g: the term is g(rest) − g0 = 0

            def term(dx, dy, dz, vx, vy, vz):
                return 0.0 * dx, 0.0 * dy, (ctx.gravity_m_s2 - g0) * dz
            return term

    class Dissipative(GravityVariation):
        name = "dissipative_test"
        CAPABILITIES = frozenset()

    register(GravityVariation)
    register(Dissipative)
    try:
        over = ["duration_s=66", "sample_rate_hz=2"]
        base = load_scene("foucault_pantheon", over)
        plain = build_instruments(base)["pendulum"]
        extra = dict(plain.effects, gravity_variation_test=GravityVariation())
        inst = type(plain)("pendulum", base.site, plain.params, extra)
        assert inst.chosen_integrator(66.0)[0] == "parareal"
        t = np.arange(0.0, 66.0, 0.5)
        a, b = inst.simulate(t), plain.simulate(t)
        assert GravityVariation.calls and GravityVariation.calls[-1] == base.site.gravity_m_s2
        for c in ("x_east", "y_north"):
            np.testing.assert_array_equal(a.columns[c], b.columns[c])
        slow = type(plain)("pendulum", base.site, plain.params, dict(plain.effects, dissipative_test=Dissipative()))
        choice, why = slow.chosen_integrator(66.0)
        assert choice == "adaptive" and "dissipative_test" in why
    finally:
        unregister("gravity_variation_test")
        unregister("dissipative_test")


def test_typed_parameters_are_frozen_and_carry_radian_views():
    """Instruments and effects read validated parameters from ``self.p``, a frozen dataclass made
    once per class from PARAMS; ``*_deg`` parameters have ``*_rad`` views equal to math.radians."""
    import dataclasses

    inst = build_instruments(load_scene("foucault_pantheon", ["duration_s=10"]))["pendulum"]
    assert inst.p.length_m == inst.params["length_m"]
    assert inst.p.initial_deflection_rad == math.radians(inst.params["initial_deflection_deg"])
    assert [f.name for f in dataclasses.fields(inst.p)] == [p.name for p in type(inst).PARAMS]
    with pytest.raises(dataclasses.FrozenInstanceError):
        inst.p.length_m = 1.0
    assert not hasattr(inst, "length_m") and not hasattr(inst, "theta0")
    assert type(inst.p) is type(build_instruments(load_scene("quet_paris", ["duration_s=10"]))["pendulum"].p)
    assert EFFECTS["spin_decay"](time_constant_s=50.0).p.time_constant_s == 50.0
