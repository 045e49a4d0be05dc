"""The names of quantities: every public name that carries a unit ends in it.

One vocabulary for arguments, options and description fields, Dataset variables and
coordinates, and JSON keys: SI throughout (``duration_s``, ``gap_m``, ``force_n``,
``limit_depth_m``), the command line and the files a user writes alone taking mm and
MPa (:data:`FILE_UNITS`: ``--gap-mm``, a design file's ``gap_mm``).  A name is a
quantity with its unit when it ends in one of :data:`UNIT_SUFFIXES`; a name for which
no unit makes sense is listed in :data:`DIMENSIONLESS` (or has one of the forms of
:data:`DIMENSIONLESS_PREFIXES` and :data:`DIMENSIONLESS_ENDINGS`); a number whose unit
is named by a sibling field is in :data:`UNIT_ELSEWHERE`.  tests/test_units.py walks
the public API and each analysis's Dataset and summary against these lists.
"""

from __future__ import annotations

#: Suffix -> the unit it stands for.  Compound units read left to right
#: (``_n_s_m``: N s/m, ``_m_s``: m/s, ``_n_m_per_rad``: N m/rad).
UNIT_SUFFIXES = {
    "_s": "s",
    "_m": "m",
    "_mm": "mm",
    "_m2": "m^2",
    "_m4": "m^4",
    "_m_s": "m/s",
    "_kg": "kg",
    "_g": "g",
    "_kg_m3": "kg/m^3",
    "_n": "N",
    "_n_m": "N/m",
    "_n_m1_5": "N/m^1.5",
    "_n_s_m": "N s/m",
    "_n_m_per_rad": "N m/rad",
    "_pa": "Pa",
    "_mpa": "MPa",
    "_hz": "Hz",
    "_rpm": "rev/min",
    "_rad": "rad",
    "_deg": "degrees",  # the cut's angles, as tool makers give them (CutGeometry)
    "_rad_s": "rad/s",
    "_j": "J",
    "_w": "W",
}

#: The units of the files a user writes and of the command line's flags (``gap_mm``,
#: ``--kr-mpa``, a ball's ``mass_g``), never of a name of the Python API.
FILE_UNITS = frozenset({"mm", "MPa", "g"})

#: Bare unit names that are quantities themselves (a speed given as ``rpm``).
UNIT_NAMES = {"rpm": "rev/min", "rpms": "rev/min"}

#: Names of numbers that have no unit: ratios, fractions, counts, indices, flags
#: stored as numbers and normalised quantities (mode shapes scaled to 1 at the tip).
DIMENSIONLESS = frozenset({
    # ratios and numbers of the model
    "ratio", "ratios", "restitution", "friction_number", "static_ratio", "damping_ratio",
    "mass_ratio", "frequency_ratio", "psi_tip", "psi_damper", "psi_absorber", "psi_force",
    "planes", "plane", "moment_scale", "mu", "mu_static", "mu_kinetic",
    "zeta", "quality", "multiplier_real", "multiplier_imag", "section_phase",
    "statistic", "error", "published_statistic", "published_error", "objective_samples",
    "stable",
    # fractions and tolerances relative to something named beside them
    "steady_fraction", "bounded_fraction", "fraction", "tolerance", "tol", "step",
    "depth_tolerance", "settle_tolerance", "force_noise", "mc", "exponent",
    "min_step", "max_step", "quantile", "u",
    # counts, indices and sizes
    "revolutions", "periods", "period", "settle_periods", "max_points", "max_branches",
    "max_k", "batch", "workers", "chunk_size", "seed", "seeds", "samples", "trials", "starts",
    "count", "distinct", "record_every", "impacts_per_cycle", "points", "nodes",
    "attractor", "attractor_id", "attractor_period", "parent", "mirror", "branch", "point",
    "sample", "event", "multiplier", "trial", "objective", "index", "case_index",
    "periodicity", "pareto", "successive", "poincare_from",
    "stop_after", "poincare_sample", "status", "events", "impact_wall", "direction",
    "dask_local", "scale", "steps_with_zero_force", "runs", "id", "zero_one_K",
    "multipliers_abs", "noise_seed", "n", "undecided_runs", "lobe", "steps",
    # labels and verdict codes (stored as numbers where a Dataset has none of them)
    "event_kind", "verdict", "verdict_bounded", "chatter", "published_chatter", "onset",
    "chatter_free", "chatter_free_by_start",
    # a confidence level
    "confidence",
    # the chance of chatter: draws, their spreads and factors, probabilities
    "draw", "draws", "draw_seed", "stiffness_cov", "damping_cov", "friction_spread",
    "restitution_spread", "ball_start", "draw_ball_start", "ball_start_drawn",
    "stiffness_scale", "damping_scale", "friction_scale", "draw_stiffness_scale",
    "draw_damping_scale", "draw_restitution", "draw_noise_seed", "draw_runs",
    "draw_runs_total", "probability", "chatter_probability", "chatter_probability_low",
    "chatter_probability_high", "chatter_probability_at_limit",
    "chatter_probability_at_limit_low", "chatter_probability_at_limit_high",
    "friction_u", "restitution_u",
    # the design page's server: a TCP port number
    "port",
})
#: Beginnings of dimensionless names (``n_modes``, ``n_samples``, ``is_bounded``).
DIMENSIONLESS_PREFIXES = ("n_", "is_", "max_index")
#: Endings of dimensionless names (``mass_ratio``, ``steady_fraction``, ``k_count``).
DIMENSIONLESS_ENDINGS = ("_ratio", "_ratios", "_fraction", "_count", "_index", "_number",
                         "_id", "_periods", "_relative", "_percent")

#: Numbers whose unit a sibling names: a sweep's ``values`` (``parameter``, and
#: ``units`` for a factory), a friction law's ``value`` and a system file ball's
#: ``friction_value`` (their ``kind``: m, 1 or N; the file's: mm, 1 or N), a
#: continuation's ``stop`` and its events' values (``parameter``), a design variable's
#: bounds and an uncertain input's draws (``name``), a state vector (its modes).
UNIT_ELSEWHERE = frozenset({
    "values", "value", "stop", "other_end", "event_value", "born_value", "choices", "x",
    "state", "friction_value",
    "low", "high", "a", "b",
    # a direction's entry under a quantity's key ({"rms_tip_m": {"forward": [...]}})
    "forward", "backward",
    # records whose columns the docstring names (time s, W m, ...)
    "impacts", "sticks", "strobe", "history", "contacts",
    # a design search's statistic, in its objective's unit (``objective_name``: m, m/N, 1)
    "objective_error", "published_objective", "objectives", "published_objectives",
    "published_samples", "improvement", "improvement_interval",
    # the uncertain parameters' draws, each in the unit its name (``uncertain``) ends in
    "uncertain_value",
})


def unit_of(name: str) -> str | None:
    """The unit ``name`` carries ("1" if dimensionless, "sibling" if another field
    names it), or None: a number under this name would carry no unit."""
    if name in UNIT_NAMES:
        return UNIT_NAMES[name]
    for suffix in sorted(UNIT_SUFFIXES, key=len, reverse=True):
        if name.endswith(suffix) and len(name) > len(suffix):
            return UNIT_SUFFIXES[suffix]
    if (name in DIMENSIONLESS or name.startswith(DIMENSIONLESS_PREFIXES)
            or name.endswith(DIMENSIONLESS_ENDINGS)):
        return "1"
    if name in UNIT_ELSEWHERE:
        return "sibling"
    return None
