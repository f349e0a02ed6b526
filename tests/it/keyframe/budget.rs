//! The exact-length search's table is refused, with a typed error, when it
//! exceeds the memory budget (`SURFMOTION_MEMORY_LIMIT`), instead of
//! aborting on the allocation. The test sets the process's environment, so
//! it runs alone in a child process of the test binary
//! (`common::alone_in_process`).

use crate::common;

use surfmotion::graph::FlatFrame;
use surfmotion::keyframe::error::SearchError;
use surfmotion::keyframe::graph::KeyGraph;
use surfmotion::keyframe::options::SearchOptions;
use surfmotion::keyframe::{Planner, Targets};

/// One sequence of 60 frames walking 2 cm a frame, with two loops back.
fn looped() -> KeyGraph {
    common::line_key_graph(60, 0.02, &[(40, 10, 0.01), (55, 30, 0.02)])
}

#[test]
fn an_exact_length_table_over_the_memory_budget_is_a_typed_error() {
    if !common::alone_in_process(
        module_path!(),
        "an_exact_length_table_over_the_memory_budget_is_a_typed_error",
    ) {
        return;
    }
    let o = SearchOptions::default();
    let p = Planner::new(looped(), &[FlatFrame::new(0), FlatFrame::new(59)], 25.0, &o).unwrap();
    let c = p.chain.as_ref().unwrap();
    // Within the default budget the query is answered.
    let t = Targets::Global {
        distance: 3.0,
        time: 8.0,
    };
    assert!(p.plan(&t, &o).is_ok());
    // A budget below the table the query needs (nodes × frames × 24 bytes).
    let need = surfmotion::keyframe::lattice::extremes_bytes(c.node_count(), 4000);
    assert!(need > 4096, "{need} bytes");
    // SAFETY: this process runs this one test (`alone_in_process`); nothing
    // else reads the environment concurrently.
    unsafe { std::env::set_var("SURFMOTION_MEMORY_LIMIT", "4K") };
    let fresh = Planner::new(looped(), &[FlatFrame::new(0), FlatFrame::new(59)], 25.0, &o).unwrap();
    let e = fresh
        .plan(
            &Targets::Global {
                distance: 30.0,
                time: 160.0,
            },
            &o,
        )
        .unwrap_err();
    assert!(matches!(e, SearchError::OverBudget(_)), "{e:?}");
    let msg = e.to_string();
    assert!(
        msg.contains("exact-length table") && !msg.contains('\n'),
        "{msg}"
    );
    let c2 = fresh.chain.as_ref().unwrap();
    assert!(c2.extremes(4000).is_err());
    unsafe { std::env::remove_var("SURFMOTION_MEMORY_LIMIT") };
    assert!(c2.extremes(4000).is_ok());
}
