"""What each command does and what it writes: the description ``penetrate COMMAND --help`` shows, one per command,
in one table (the one-line help beside each parser is what ``penetrate --help`` lists)."""

from __future__ import annotations

__all__ = ["DESCRIPTIONS", "JSON_SHAPES"]

DESCRIPTIONS = {
    "run": (
        "Run one scene from impact to its end and print its summary: depth, path, attack angles, end reason and"
        " warnings. With --out, writes summary.json and history.csv there; --json prints the summary as one object."
    ),
    "sweep": (
        "Run variations of a scene (--grid over scene keys, --list of override sets) in parallel, each run kept in"
        " the run store, so that running the sweep again runs only what is new. Prints a row per run; writes sweep.csv"
        " (every summary field of each run) and sweep.md into --out."
    ),
    "critical": (
        "Find the critical impact velocity: the speed above which the scene's disturbed trajectory turns unstable,"
        " searched inside --speeds LOW:HIGH to --resolution by full runs, the first bracket placed by the reduced"
        " model where it applies. Prints each run and the bracket; writes no file."
    ),
    "convergent": (
        "Measure the characteristic convergent velocity: the speed at which an unstable run's attack angle comes"
        " back below the threshold, the impact speed raised until a run turns unstable. Prints each run and the"
        " velocity; writes no file."
    ),
    "map": (
        "The critical impact velocity over a grid of one or two scene keys (--grid), each point a guided search,"
        " resumable from the run store. Writes map.csv, map.json, map.md and map.png into --out."
    ),
    "ballistic-limit": (
        "Find the ballistic limit of a target with a rear face: the lowest impact speed that perforates it, searched"
        " inside --speeds LOW:HIGH to --resolution. Prints each run, the limit and the residual velocities; writes"
        " no file."
    ),
    "predict": (
        "Predict both characteristic speeds from the reduced pitch-plane model (a body of revolution in a"
        " homogeneous target) without a full trajectory, in about a second. Prints the speeds, the model and its"
        " runs; writes no file."
    ),
    "compare": (
        "Run a scene, or every shot of a test series, under several resistance laws side by side: depths, paths and"
        " stability, and with --critical each law's critical speed. Writes compare.csv, compare.json, compare.md"
        " and compare.png into --out."
    ),
    "accuracy": (
        "What accuracy costs in time: the scene at several mesh sizes, RK4 steps, Dormand-Prince tolerances and"
        " quadrature orders, each run's error against the finest and its wall time. Writes accuracy.csv,"
        " accuracy.md and accuracy.png into --out."
    ),
    "contact": (
        "What the contact ramp changes: the scene from its contact incidence down to the sharp switch at Vn = 0,"
        " with the change in depth and path. Writes contact.csv and contact.md into --out."
    ),
    "entry": (
        "What the entry smoothing changes, and the Runge-Kutta time error with it: the scene at several smoothing"
        " lengths and time steps. Writes entry.csv and entry.md into --out."
    ),
    "paper": (
        "Regenerate the paper's study: the critical and convergent velocities of its seven projectiles, their"
        " fits, the load-only prediction and the figures. Writes results.md, results.json and the figures into"
        " --out (docs/paper by default)."
    ),
    "validate": (
        "Run every shot of a test series (a CSV file of measured shots) and set each prediction beside its"
        " measurement, with the error. Writes validate.csv, validate.json, validate.md and validate.png into --out."
    ),
    "ensemble": (
        "Monte Carlo over sampled impact conditions (--sample KEY=DISTRIBUTION): the probability of each outcome"
        " with its interval, binned (--by) or multi-fidelity (the reduced model sorts the samples) if asked."
        " Resumable; writes ensemble.csv, ensemble.json, ensemble.md and its figures into --out."
    ),
    "fit": (
        "Fit numeric scene keys to observed quantities (of a scene, or of a test series' shots) by least squares,"
        " with their standard errors. Writes fit.json, fit.md and fit.png into --out; nothing when the observations do"
        " not determine the fit."
    ),
    "formulas": (
        "Evaluate the field's empirical equations for the scene's projectile, impact speed and concrete target:"
        " depth of penetration by Young, the modified NDRC, ACE, UKAEA and Li and Chen, with scabbing and"
        " perforation thicknesses where a formula gives them, each checked against the ranges of its data."
        " Prints the table; writes formulas.md and formulas.json into --out."
    ),
    "render": (
        "Run one scene and draw its resistance field off-screen: the body coloured by the normal stress at chosen"
        " instants, its trajectory, the resistance centre and a polar plot; an animation and ParaView files if"
        " asked. Writes the pictures into --out."
    ),
}

#: what each command's ``--json`` prints: one JSON object, its top-level keys (and what the rest holds)
JSON_SHAPES = {
    "run": "the run's summary: the fields of summary.json (the run outputs' reference)",
    "sweep": '`{"rows": [...]}`: a row per run, the varied keys and every summary field',
    "critical": "`critical_velocity`, `bracket`, `indicator` (every run), `message`, `fix`, `runs`, `rounds`,"
    " `guide`, `guide_text`, `predicted_velocity`",
    "convergent": "`characteristic_convergent_velocity`, `runs`, `message`, `guide`, `guide_text`",
    "map": "the map's record, as map.json: the grid's `keys`, `points` (a search each), `speeds`, `resolution`,"
    " the runs",
    "ballistic-limit": "`ballistic_limit`, `bracket`, `runs`, `full_runs`, `rounds`, `message`, `guide`,"
    " `predicted_limit`",
    "predict": "`characteristic_convergent_velocity`, `critical_velocity`, `critical_bracket`, `model`,"
    " `assumptions`, `runs`, `messages`, `prediction_time`, `wall_time`",
    "compare": '`{"rows": [...]}` (a row per law) and, with --depths-at, `depths_at`; with --series the record of'
    " compare.json: `series`, `ranking`, `shots`",
    "accuracy": "`reference` (the finest run) and `settings` (a row per setting)",
    "contact": '`{"rows": [...]}`: a row per contact incidence',
    "entry": '`{"rows": [...]}`: a row per entry smoothing and step',
    "paper": "the record of results.json (variants.json with --variants)",
    "validate": "the record of validate.json",
    "ensemble": "the record of ensemble.json",
    "fit": "the record of fit.json",
    "formulas": "`inputs` (what the formulas took from the scene), `formulas` (a list: `name`, `depth`, `valid`,"
    " `checks`, `scabbing`, `perforation`, `source`), `messages`",
    "render": "the files written and the timings",
}
