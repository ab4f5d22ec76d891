//! The boundary search on synthetic scans whose transitions are known
//! exactly (issue #12 item 3): every transition found, each bisected to the
//! stated tolerance, first failure and last pass per criterion, and the
//! non-monotone flag.

use anyhow::Result;
use ehservo::reproduce::breaking::{search_with, PointStatus, Scan, ScanPoint, Transition};

/// Diverged on [0.30, 0.3237) ∪ [0.4113, ∞); e_max = 10·x deg elsewhere, so
/// with a 0.5° limit it tracks below x = 0.05 exactly.
fn synthetic(x: f64) -> Result<ScanPoint> {
    let diverged = (0.30..0.3237).contains(&x) || x >= 0.4113;
    Ok(ScanPoint {
        x,
        e_max_deg: if diverged { None } else { Some(10.0 * x) },
        diverged_at_s: if diverged { Some(1.0) } else { None },
    })
}

fn contains(t: &Transition, edge: f64) {
    assert!(
        t.lo < edge + 1e-12 && edge <= t.hi + 1e-12,
        "edge {edge} outside the bracket {}–{}",
        t.lo,
        t.hi
    );
}

#[test]
fn every_transition_is_found_and_bisected() {
    // Grid 0, 0.01, …, 0.6 (61 points); brackets ≤ 0.002 wide.
    let grid = Scan::new(0.0, 0.6, 0.01);
    assert_eq!(grid.points, 61);
    assert!((grid.tol - 0.002).abs() < 1e-15);
    let s = search_with(grid, &synthetic, 0.5).unwrap();
    assert_eq!(s.scan.len(), 61);

    // Bounded: fails at 0.30, passes again from 0.3237, fails for good at 0.4113.
    let b = &s.bounded;
    assert_eq!(b.transitions.len(), 3, "{:?}", b.transitions);
    let edges = [0.30, 0.3237, 0.4113];
    let fails = [true, false, true];
    for ((t, e), f) in b.transitions.iter().zip(edges).zip(fails) {
        contains(t, e);
        assert!(
            t.hi - t.lo <= 0.002 + 1e-15,
            "bracket {t:?} wider than the tolerance"
        );
        assert_eq!(t.fails, f);
    }
    assert!(b.non_monotone);
    // First failure: the right end of the first bracket (a failing x); last
    // pass: the left end of the last failing bracket (a passing x).
    let ff = b.first_fail.unwrap();
    assert!((0.30..0.302).contains(&ff), "first failure {ff}");
    assert!(synthetic(ff).unwrap().diverged_at_s.is_some());
    let lp = b.last_pass.unwrap();
    assert!((0.4093..0.4113).contains(&lp), "last pass {lp}");
    assert!(synthetic(lp).unwrap().diverged_at_s.is_none());

    // Tracking: e_max = 10x < 0.5 only below 0.05, one transition.
    let t = &s.tracking;
    assert_eq!(t.transitions.len(), 1, "{:?}", t.transitions);
    contains(&t.transitions[0], 0.05);
    assert!(!t.non_monotone);
    assert!(t.last_pass.unwrap() < 0.05 && t.first_fail.unwrap() >= 0.05);
    assert_eq!(s.scan[0].status(0.5), PointStatus::Tracking);
    assert_eq!(s.scan[10].status(0.5), PointStatus::Bounded);
    assert_eq!(s.scan[30].status(0.5), PointStatus::Diverged);
}

#[test]
fn a_scan_that_never_fails_or_always_fails() {
    let grid = Scan::new(0.0, 1.0, 0.1);
    let ok = |x: f64| -> Result<ScanPoint> {
        Ok(ScanPoint {
            x,
            e_max_deg: Some(0.1),
            diverged_at_s: None,
        })
    };
    let s = search_with(grid, &ok, 0.5).unwrap();
    assert_eq!(s.bounded.first_fail, None);
    assert_eq!(s.bounded.last_pass, Some(1.0));
    assert!(s.bounded.transitions.is_empty() && !s.bounded.non_monotone);

    let bad = |x: f64| -> Result<ScanPoint> {
        Ok(ScanPoint {
            x,
            e_max_deg: None,
            diverged_at_s: Some(0.1),
        })
    };
    let s = search_with(grid, &bad, 0.5).unwrap();
    assert_eq!(s.bounded.first_fail, Some(0.0));
    assert_eq!(s.bounded.last_pass, None);
    assert_eq!(s.tracking.first_fail, Some(0.0));
}

#[test]
fn failing_at_the_start_then_recovering_is_non_monotone() {
    // Diverged below 0.25 only: the first failure is the grid's start and the
    // one transition is a recovery.
    let f = |x: f64| -> Result<ScanPoint> {
        let d = x < 0.25;
        Ok(ScanPoint {
            x,
            e_max_deg: (!d).then_some(0.1),
            diverged_at_s: d.then_some(0.5),
        })
    };
    let s = search_with(Scan::new(0.0, 1.0, 0.1), &f, 0.5).unwrap();
    assert_eq!(s.bounded.first_fail, Some(0.0));
    assert_eq!(s.bounded.last_pass, Some(1.0));
    assert_eq!(s.bounded.transitions.len(), 1);
    assert!(!s.bounded.transitions[0].fails);
    contains(&s.bounded.transitions[0], 0.25);
    assert!(s.bounded.non_monotone);
}
