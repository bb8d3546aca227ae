//! The names of the column-collapse results, which validation checks a scene's `[[checks]]`
//! against before the analysis that produces them runs.

/// Names of the column-collapse results (prefixed `collapse.` in a run), in the order of
/// `analysis::collapse::collapse_results`.
pub const QUANTITIES: [&str; 10] = [
    "runout",
    "final_height",
    "aspect_ratio",
    "front_m",
    "height_m",
    "initial_length_m",
    "initial_height_m",
    "stop_time",
    "dem_law_ratio",
    "experiment_ratio",
];

/// Names of the thick-front results (prefixed `collapse.`), in the order of
/// `analysis::collapse::thick_front_results`.
pub const THICK_QUANTITIES: [&str; 3] = ["thick_front_m", "thick_runout", "thick_experiment_ratio"];
