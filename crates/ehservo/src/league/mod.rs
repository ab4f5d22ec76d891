//! `ehservo league SUITE`: every controller of a suite — tuned with the
//! same budget, or with given parameters — on every scenario of the suite,
//! with a robustness margin, reported as `league.md`, `league.html` and
//! `league.csv`.
//!
//! ```toml
//! name = "paper"
//! description = "..."
//!
//! [[controller]]              # tuned by `[tuning]` (the default)
//! kind = "pid"
//!
//! [[controller]]              # given parameters, not tuned
//! kind = "nnvsc"
//! name = "nnvsc-paper"        # its label (default: the kind)
//! tune = false
//! params = { gamma1 = 10.0 }  # on top of the kind's defaults
//!
//! [[scenario]]
//! file = "../paper/fig8.toml" # relative to the suite file
//! name = "fig8-mc"            # default: the file's stem
//! set = ["simulation.horizon=5"]   # overrides, as `ehservo run --set`
//! draws = 20                  # uncertainty draws (uncertainty.seed = first_seed, first_seed + 1, …)
//! first_seed = 10             # default 0 (with one draw: the scenario's own seed)
//! [scenario.box]              # optional: the worst case over a box of keys,
//! keys = { "plant.m" = [0.05, 0.3] }   # its 2^k corners and `draws` points
//! draws = 20                  # drawn inside (param_box), each run per seed
//!
//! [tuning]                    # the one budget every tuned controller gets:
//! scenarios = ["../paper/fig2.toml"]   # the keys of an `ehservo tune` file
//! budget = 2000               # (no `name`, `controller` or `[[param]]`:
//! objective = "worst"         #  each kind's declared tunables are searched)
//! draws = 4
//! [tuning.penalty]
//! u_limit = 10.0
//!
//! [margin]                    # the robustness margin, bisected
//! scenario = "../paper/fig3.toml"
//! keys = ["uncertainty.a_bias", "uncertainty.b_bias"]   # set together to scale·x
//! scale = 1.0                 # default 1; −1 bisects a negative bias
//! low = 0.0                   # x known bounded for a sane controller
//! high = 10.0                 # the largest x tried
//! tolerance = 0.01
//! e_limit_deg = 5.0           # optional: e_max above it counts as unbounded
//! ```
//!
//! Every controller runs with one full `[controller]` table on every
//! scenario: the kind's defaults, with the given `params` or the tuned
//! values on top. Each run of the report is a scenario file written under
//! `scenarios/`, which `ehservo run` reproduces (other draws with
//! `--set uncertainty.seed=S`).
//!
//! The margin is the largest x in [low, high] for which the margin
//! scenario with every key set to scale·x stays bounded (not diverged, and e_max
//! within `e_limit_deg` when given), found by bisection to `tolerance`
//! between a bounded `low` and an unbounded `high`. It assumes one
//! boundary: a controller that is bounded again above its first failure is
//! not seen. `high` bounded reports "≥ high"; `low` unbounded "< low".
//!
//! Runs are pure functions of (suite, controller, scenario, draw) and are
//! collected in order, so the outputs are the same bit for bit whatever
//! the thread count.

mod margin;
pub mod param_box;
mod play;
pub mod report;
mod suite;

pub use margin::{Margin, MarginResult};
use play::build_with;
pub use play::{league_to_dir, play, Cell, LeagueResult, Standing};
pub use suite::{
    Case, Contestant, ControllerEntry, League, MarginCfg, ScenarioEntry, Source, SuiteFile,
    TuningCfg, MAX_DRAWS,
};
