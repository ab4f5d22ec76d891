//! `ehservo tune`: a controller's parameters searched to minimise an
//! objective over a set of scenarios, by argmin's particle swarm.
//!
//! ```toml
//! name = "pid-fig2"
//! scenarios = ["../paper/fig2.toml"]   # relative to this file
//! controller = "pid"                    # the kind tuned (default: the first scenario's)
//! budget = 2000                         # evaluations of the objective
//! particles = 40
//! seed = 1
//! objective = "mean"                    # or "worst", over scenarios × draws
//! draws = 1                             # uncertainty seeds per scenario (uncertainty.seed = 0, 1, …)
//! [penalty]
//! chattering = 0.0                      # + weight·chattering index
//! u_limit = 10.0                        # V; + u_excess·max(0, u_max − u_limit)
//! u_excess = 1.0
//! [reject]
//! saturation_share = 0.2                # a run at the command's limit longer than this share: +∞
//! [verify]
//! horizon_factor = 2.0                  # the choice re-run at 2× each scenario's horizon …
//! draws = 3                             # … over these draws (default: `draws`, at least 3)
//! [[param]]                             # default: the kind's declared tunables
//! key = "kp"
//! low = 1.0
//! high = 1000.0
//! scale = "log"
//! ```
//!
//! One evaluation runs every scenario (× draws) with the candidate
//! parameters and scores it: e_max after the transient (°), plus the
//! penalties; a run that diverges, hits an end stop, ends in a sustained
//! oscillation or saturates beyond `[reject] saturation_share`
//! ([`crate::behaviour`]), or parameters the controller refuses, score +∞.
//! The parameters chosen are then verified ([`Tune::verify`]): every
//! scenario at `[verify]`'s longer horizon and over its draws, held to the
//! same rules. No finite objective, or a failed verification, is a failed
//! tune ([`TuneResult::failure`]): no tuned.toml, exit 1. The swarm (Zambrano-Bigiarini et al., SPSO 2011, as argmin
//! implements it) searches a log-scaled parameter as its log10. Its random
//! numbers come from a seeded generator, and the particles of an
//! iteration are evaluated in parallel by rayon and collected in order,
//! so a seed gives the same result bit for bit whatever the thread count.

mod file;
mod score;
mod search;
mod verify;

pub use file::{
    common_axis, declared, Objective, ParamRange, Penalty, Reject, Scale, Tune, TuneFile, Verify,
    MAX_BUDGET,
};
pub(crate) use file::{default_budget, default_draws, default_particles, default_seed};
pub(crate) use file::{not_a_result, numeric};
pub use score::Evaluation;
pub use search::{search, tune_to_dir, SwarmBest, TuneResult};
pub use verify::{Verification, VerifiedRun};
