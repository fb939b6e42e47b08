//! Collocation chaoses too small to judge themselves: one node (one run at the centre) and
//! order 1 (all the variance in the top order), on Ishigami through the Functions test FMU.

use serde_json::Value;

use crate::study_chaos::run_ishigami;
use crate::support::{assert_contains, summary, test_fmus};

/// The summary of Ishigami by SCM on `nodes` nodes per input; `None` without the test FMUs.
fn ishigami_scm(nodes: usize) -> Option<Value> {
    test_fmus::built()?;
    let dir = tempfile::tempdir().unwrap();
    let method = format!("kind = \"scm\"\nnodes = {nodes}");
    Some(summary(&run_ishigami(
        dir.path(),
        &format!("scm{nodes}"),
        &method,
    )))
}

/// `nodes = 1` was accepted by the study's checks (1 to 64), then the run stopped with "only
/// 1 successful runs: nothing to analyse"; a sparse grid of level 0 (also one run) worked.
#[test]
fn scm_with_one_node_is_one_run_at_the_centre_and_says_it_estimates_no_scatter() {
    let Some(s) = ishigami_scm(1) else {
        return;
    };
    assert_eq!(s["model_runs"], 1);
    // Ishigami at the centre of U(−π, π)³: sin 0 + 7 sin² 0 + 0.1 · 0 · sin 0 = 0.
    let y = &s["quantities"]["Y"];
    assert_eq!(
        (y["mean"].as_f64(), y["std"].as_f64()),
        (Some(0.0), Some(0.0))
    );
    assert_contains(
        &s["warnings"].to_string(),
        "`nodes = 1` is one run at the centre",
    );
}

/// On 2 nodes per input a chaos of order 1 has all its variance in its top order, whatever
/// the model: it warned "the top order of the chaos holds 100.0 % ... has not converged"
/// for every quantity, which says nothing of convergence.
#[test]
fn a_chaos_of_order_1_is_told_it_cannot_judge_its_convergence() {
    let Some(s) = ishigami_scm(2) else {
        return;
    };
    let warnings = s["warnings"].to_string();
    assert_contains(&warnings, "Y: a chaos of order 1 has all its variance");
    assert!(
        !warnings.contains("the top order of the chaos holds"),
        "{warnings}"
    );
}
