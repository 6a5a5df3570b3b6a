"""The estimate's long descriptions (msg_docs/estimate.md before it was generated), one per object or key
whose meaning takes a paragraph; the records (:mod:`.estimate_types`, :mod:`.entries`, :mod:`.north.block`)
name them and the schema carries them."""

HEMISPHERE = (
    '`north`, `south` or `not determined by these instruments`, and why: measured (the sign of a '
    "sign-sensitive measurement — a pendulum's k = n sin γ, or a gyroscope plane tilted out of the "
    'horizontal and the meridian — with the Δχ² by which the other hemisphere fits worse), assumed '
    '(`estimator.hemisphere` in the scene, used only when no measurement decides; a measured sign '
    "overrules it and says so), or not determined (item 9 and the gimbal's T'/T'' fix cos γ only)")

EARTH_RATE_KNOWN = (
    "`true` when n was not estimated but held at the scene's `site.earth_rate_rad_s` (IERS conventional "
    '7.292115e-5 rad/s by default) and the latitude fitted alone: where the instruments cannot separate n'
    ' and γ (a pendulum alone: k = n sin γ; one horizontal gyroscope: n cos γ), or under '
    '`estimator.earth_rate: known`; `earth_rate_basis` says which, and why (`estimator.earth_rate: '
    "estimate` refuses instead: latitude `null` with the reason). A pendulum's k then decides the "
    'hemisphere (sin γ is odd)')

CHECKS = (
    'the adequacy checks of the data (estimators/adequacy.py), one entry per instrument and check: '
    "`instrument`, `check` (`amplitude`: the swing against the scene's release, at most 30×, never beyond"
    ' π; `sampling`: samples per predicted period, at least 2.5; `signal`: detection A²N/(4σ²) ≥ 100 with'
    " σ at least a double's resolution of an angle; `period`: fitted against the scene's prediction, "
    "within a factor 4; `fit`: a gyroscope's χ²/dof against the sensor model, a pendulum's swing-plane "
    "azimuths against the noise the record shows; `halves`: a pendulum's plane rate over the first half "
    "of the record against the second's, flagged beyond 4 σ; `site`: each pendulum's Foucault rate "
    "against n sin γ at the scene's site, and a combination with a gyroscope's latitude (and an estimated"
    " Earth rate) against the site's, `failed` beyond 4 σ with what was measured and the likely causes — "
    'a driven or damped pendulum, an anisotropic support, a wrong length or scale, the wrong scene — the '
    'estimate still reported and the exit status 0), `status` (`passed`, `flagged` with the figure, '
    "`failed` (the `site` check: the estimate disagrees with the scene's site), `no_signal`: that "
    'instrument is `null` with a reason, `not_applicable`), `value`, `expected`, `detail`. A check that '
    'no estimate can survive is not in the JSON: the command exits 2 with one line naming the check, both'
    ' numbers and the likely cause ("time looks like milliseconds; pass --time-unit ms", "angles look '
    'like degrees", an alias, a scene that does not describe the instrument, χ²/dof above 100)')

REASON = (
    'why the combined latitude (or n) is `null`: no Earth-rate measurement, one that gives only n·s(γ) (a'
    ' pendulum alone: k = n sin γ) under `estimator.earth_rate: estimate` or in a scene without '
    '`earth_rotation`, or measurements that cannot separate n and γ (all with the same s(γ), e.g. two '
    "horizontal gyroscopes: only n cos γ; all in planes containing Earth's axis: n alone, their weighted "
    'mean)')

SCENE_NOTES = (
    'list of sentences on what the scene leaves out that a reader would assume, e.g. `earth_rotation is '
    "not simulated: ...` (no instrument has the Earth's rotation: a pendulum's k = 0 then says nothing "
    'about the site); empty when there is nothing to say. See [scene.md](../docs/formats/scene.md)')

INSTRUMENTS = (
    "per instrument: gyroscopes `swing_duration_s` (Quet's T, one swing = half a period) ± "
    '`swing_duration_sigma_s`, `small_amplitude_swing_duration_s` (T / (2/π)K(sin(a/2))), '
    "`amplitude_rad`, `mean_spin_rad_s`, `crlb_swing_duration_s`, `counting` (Quet's method: "
    '`swing_duration_s`, `swings`), `fit_method`, `notes`; pendulums `foucault_rate_rad_s` ± '
    '`foucault_rate_sigma_rad_s` (the exact elliptic-integral ellipse correction inverted), '
    "`crlb_foucault_rate_rad_s` (Cramér–Rao bound from the scene's sensor noise √(σ² + q²/12), dropouts "
    "as fewer samples: the plane's rate and the areal velocity; 0 without noise), `ellipse_scale` (how "
    'the ellipse (Airy) correction hangs on the position scale: `exponent` 2 — it is (3/8) a b/l² times '
    'the swing frequency, so a scale s times the assumed one multiplies it by s² while the measured turn '
    'is unchanged — `share_of_measured_rate`, `k_without_correction_rad_s`, `k_at_half_scale_rad_s`, '
    '`k_at_double_scale_rad_s`, and `matters`: halving the scale would move k by more than its σ; the '
    'text then says so beside k), `measured_plane_rate_rad_s` ± `measured_plane_rate_sigma_rad_s` (the '
    "swing plane's turn as measured, before the ellipse correction), `sigma_basis` (`white`: σ from the "
    "record's noise through the Cramér–Rao bound, the azimuths scattering as white noise does; `record "
    "scatter`: the azimuths' χ²/dof, their swing-to-swing autocorrelation or the halves' disagreement say"
    " the residuals are not white, and σ of every rate and of the period is the largest of the residuals'"
    ' scatter, the Newey–West HAC standard error (Econometrica 55 (1987) 703) and the line through blocks'
    ' of consecutive swings (blocking, Flyvbjerg and Petersen, J. Chem. Phys. 91 (1989) 461); the '
    "period's at least half its halves' difference; estimators/scatter.py) with `sigma_basis_detail`, "
    '`ellipse_correction_rad_s`, `amplitude_rad`, `minor_axis_rad`, `period_s` ± `period_sigma_s`, '
    "`rest_point` (the swing's centre fitted, not assumed: `east_rad`, `north_rad` at `at_time_s` and its"
    ' drift `drift_east_rad_s`, `drift_north_rad_s`; the deflections are taken about it, so a track whose'
    ' origin is not the rest point gives the same rate); or `null` fields and `reason`; another '
    "measurement kind's entry as that kind gives it (a plug-in's, docs/extending.md). Every instrument of"
    ' the scene has an entry in `estimate`, the live estimate of `run` and `replay` alike: one the '
    "estimator does not measure (no registered measurement kind: a free gyroscope, Puiseux's body) has "
    '`type` and the `reason` `not used by the estimator (...)`')

SITE = (
    "the scene's site as evidence: `latitude_known` (`false` when the scene says `site.latitude_known: "
    'false` — in the YAML or `--set site.latitude_known=false` — for a record from an unknown place: '
    'nothing is compared and the estimate reads as before), `latitude_deg`, `earth_rate_rad_s`, '
    '`expected_foucault_rate_rad_s` (n sin γ), `agrees`, `disagreements` (per failed `site` check: '
    "`instrument`, `z`, the measured and expected rates, `headline`). When a check fails, the text's "
    "first lines are the measured rate beside a free pendulum's at the site, and the latitude is printed "
    'as "if the pendulum were free"; `latitude_deg`/`latitude_sigma_deg` keep their meaning (the latitude'
    ' the record gives for a free pendulum)')

NORTH = (
    'present whenever the scene has a horizontal plane gyroscope (flat plane, rotor on): its observation '
    'measures an azimuth beside its swing rate (an unstated `mount_azimuth_deg` reads as 0: the scale '
    "reads Quet's u, and every other result is as before issue 24) (estimators/north/estimate.py). The "
    "block of the instrument with the smallest σ (each instrument's own is `instruments.<name>.north`): "
    "`instrument`; `mount_azimuth_deg` — the azimuth, clockwise from true north, of the scale's zero (the"
    " instrument's `mount_azimuth_deg`; the measured `angle` reads counter-clockwise like Quet's u, so "
    'true north reads +mount_azimuth, and −angle = azimuth − mount), from the exact fit '
    '(estimators/north/exact.py: the swing equation itself — the sine law about north, the tape toward '
    'its drifting zero, the damping — fitted jointly to the rotor-on and rotor-off records; no '
    'linearisation, so the answer holds for any mount azimuth and any swing the scene produces); '
    '`sigma_arcsec` its σ, the Cramér–Rao bound of the whole problem (tape calibration included) at the '
    "estimate, with the sensor model's σ (the residuals' when the sensor states none); `crlb_arcsec` that"
    ' bound; `method` (`fit`); `tape` (`null` without `tape_torsion`): `instrument` (the rotor-off swing;'
    ' its own `mount_azimuth_deg` is irrelevant: no directing torque), `ratio_db_dk` ± `ratio_sigma` (the'
    " fit's k_B/K), `zero_reading_deg` (the tape zero at mid-record, counter-clockwise scale reading), "
    '`zero_sigma_arcsec`, `zero_rate_arcsec_h` (its fitted drift), `surveyor_ratio` ± '
    "`surveyor_ratio_sigma` (the reversal-point methods' calibration: T_on²/(T_off² − T_on²) from "
    'undamped periods, ω_u² = ω_d² + δ²), `source`; `methods`: `schuler_mean`, `lavrov`, `transit`, '
    '`fit`, each `mount_azimuth_deg`, `sigma_arcsec`, `sigma_source`, `n_used` (reversal points, transits'
    " or samples), `needs` (what it must observe), `bias` (its model's biases, in words), `bias_arcsec` "
    "(its bias in this set-up, in mount azimuth: the method run on the fitted model's own noise-free "
    "records, less the model's answer; 0 for the fit) and `bias_flagged` (true when |bias| > σ/4: that "
    "method's number is not to be used as north here), `notes`, `period_s` where it gives one, "
    '`crlb_arcsec` (fit); the reversal-point methods are tape-corrected with the exact relation N = c − '
    'atan(x (Z − c)) (x from undamped periods, Z the rotor-off centre at mid-record with its fitted '
    "drift); the headline is always the fit; `pre_orientation`: `centre_from_north_deg` (the swing's "
    'equilibrium on the scale, clockwise from north), `tape_zero_from_north_deg`, '
    "`linear_tape_law_error_arcsec` (what N = c + x(c − Z) would err by), `cost_arcsec` (each method's "
    '`bias_arcsec`); `refused`: method → why; `notes`. No directing torque (a pole, no `earth_rotation`):'
    ' every number `null`, `interval_deg` [0, 360] and `reason`. One swing longer than the record: for an'
    ' instrument that asks for north (states `mount_azimuth_deg` or hangs on a `tape_torsion`) exit 2 '
    'naming `site.latitude_deg`, the swing and the latitude limit for that duration; for one that does '
    'not, the block is `null` in every number with `interval_deg` [0, 360] and that `reason` (so is a '
    'record the methods cannot reduce, a fit refused) — never an exit 2 and no failed check. A tape '
    'without its rotor-off swing: exit 2 naming `instruments.<name>.rotor_off_instrument`; with it in the'
    ' scene, a table (`--data`) without its `angle` column exits 2 naming the column, a bag (`replay`) '
    'without its joint states exits 2 naming the topic. `estimate`, `estimate --data` of the table '
    '`simulate` writes and `replay` of the bag `run --bag` records build the same record (the scale '
    "reading u + M and the rotor-off swing's) and give the same block")

RATE_NORTH = (
    'a `rate_gyro` (a single-axis gyro on a turntable, issue 35) gives the same block '
    '(estimators/north/rate_gyro.py), `instrument` naming it: `mount_azimuth_deg` — the azimuth, '
    "clockwise from true north, of the turntable's reference (index 0; the sensitive axis points at mount"
    " + index) — by generalised least squares of r = A cos(M + φ) + b with the sensor's own noise "
    'covariance (white angle random walk + Gauss–Markov bias instability, exact for the bin means it '
    "fits: each held position's run, a carousel's turn in 10° bins, cut to τ_c/16); `sigma_arcsec` = "
    '`crlb_arcsec`, the Cramér–Rao bound of those bin means (`fisher`: `matrix`, `parameters` a, c, b — '
    'or d, b with two positions —, `formula`); `method` `gls`; `tape` and `pre_orientation` `null`; '
    '`methods.gls` and, for four positions at 90° steps, `methods.closed_form` (N = atan2(r_90 − r_270, '
    'r_0 − r_180), `north_index_deg`, `position_means_rad_s`, σ propagated through the same covariance); '
    '`bias` (`rate_rad_s`, `sigma_rad_s`, `deg_h`, `sigma_deg_h`: the turn-on bias plus the bias '
    "instability's mean over the record); `scale_factor` (≥ 3 headings: `amplitude_rad_s` ± "
    '`amplitude_sigma_rad_s`, `ppm` ± `sigma_ppm` = A/(n cos γ) − 1 at the stated latitude; two '
    'positions: `assumed_ppm` 0 and `mount_shift_arcsec_per_100ppm`, the bias a scale factor error '
    "makes); `sign` (`resolved_by`: `data` with three or more headings, `prior` when two positions' "
    "mirror image −M − 2φ0 lies outside the scene's `mount_azimuth_prior_deg` ± "
    '`mount_azimuth_prior_tolerance_deg`, `null` when the prior does not exclude it — then '
    '`mount_azimuth_deg` is `null` with `reason`; `candidates_deg`, `detail`); `undetermined` (what the '
    'data cannot give: latitude and scale factor apart — one horizontal axis reads (1 + s) n cos γ —, the'
    ' vertical rate n sin γ, and with two positions the amplitude itself); `noise_model` '
    '(`sigma_white_rad_s`, `sigma_gm_rad_s`, `correlation_time_s`, `dt_s`, `bins`, `samples`); '
    '`residual_chi2_per_dof`; `positions` (held headings, `null` for a carousel); `notes`. One heading: '
    "`null` with `reason`. A rate gyro gives no Earth-rate measurement: its entry's `reason` says so, and"
    ' the latitude is `null` unless other instruments give it')

LATITUDE = (
    'combined latitude and its 1-σ half-interval (profile likelihood, Δχ² = 1) of the one mode reported; '
    '`latitude_deg` is |γ| when `latitude_is_absolute`; `latitude_sigma_deg` is `null` when the '
    'likelihood is not locally Gaussian (its Δχ² = 9 region reaches a pole or, for |γ|, the equator), '
    'with `latitude_sigma_reason`')

ITEM9 = (
    'Quet item 9: `cos_latitude` = (T_m/T_h)² ρ_m/ρ_h (with finite-amplitude, spin and ring-inertia '
    "corrections), `latitude_deg` (signed by the combination's `hemisphere`, else |γ| with "
    '`latitude_is_absolute`), `uncorrected_cos_latitude` (raw (T_m/T_h)²)')
