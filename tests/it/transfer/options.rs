//! The validated constructors of the transfer and codec options (issue 40):
//! each accepts its documented defaults, equals the struct built field by
//! field, and refuses every value outside its range with a message naming
//! the field.

use surfmotion::jobs::transfer::{AutoScanLandmarks, ScanTransferOptions};
use surfmotion::transfer::MarkerOptions;
use surfmotion::web::codec::{DEFAULT_LEVEL, EncodeOptions, Predictor};

#[test]
fn marker_options_new_checks_count_and_margin() {
    let d = MarkerOptions::default();
    assert_eq!(MarkerOptions::new(d.count, d.margin).unwrap(), d);
    for margin in [0.0, 0.5] {
        assert_eq!(MarkerOptions::new(20, margin).unwrap().margin, margin);
    }
    for (count, margin, field) in [
        (0, 0.25, "count"),
        (180, -0.01, "margin"),
        (180, 0.51, "margin"),
        (180, f64::NAN, "margin"),
        (180, f64::INFINITY, "margin"),
    ] {
        let e = MarkerOptions::new(count, margin).unwrap_err().to_string();
        assert!(e.contains(&format!("MarkerOptions::{field}")), "{e}");
    }
}

#[test]
fn encode_options_new_checks_error_bound_and_level() {
    let d = EncodeOptions::default();
    let o = EncodeOptions::new(d.max_error, d.predictor, d.level).unwrap();
    assert_eq!(
        (o.max_error, o.predictor, o.level),
        (0.001, Predictor::SpatioTemporal, DEFAULT_LEVEL)
    );
    assert_eq!(
        EncodeOptions::new(0.1, Predictor::Temporal, 9)
            .unwrap()
            .level,
        9
    );
    for (max_error, level, field) in [
        (0.0, 5, "max_error"),
        (-1e-3, 5, "max_error"),
        (f64::NAN, 5, "max_error"),
        (f64::INFINITY, 5, "max_error"),
        (1e-3, 10, "level"),
    ] {
        let e = EncodeOptions::new(max_error, Predictor::Temporal, level)
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("EncodeOptions::{field}")), "{e}");
    }
}

#[test]
fn transfer_options_new_check_confidence_rate_and_markers() {
    let d = AutoScanLandmarks::default();
    let a = AutoScanLandmarks::new(d.min_confidence, None).unwrap();
    assert_eq!((a.min_confidence, a.write), (0.5, None));
    for c in [-0.1, 1.1, f64::NAN] {
        let e = AutoScanLandmarks::new(c, None).unwrap_err().to_string();
        assert!(e.contains("min_confidence"), "{e}");
    }
    let d = ScanTransferOptions::default();
    let o = ScanTransferOptions::new(d.markers, d.fps).unwrap();
    assert_eq!((o.markers, o.fps), (d.markers, 30.0));
    for fps in [0.0, -30.0, f64::NAN, f64::INFINITY, 1e9] {
        let e = ScanTransferOptions::new(d.markers, fps)
            .unwrap_err()
            .to_string();
        assert!(e.contains("ScanTransferOptions::fps"), "{e}");
    }
    let bad = MarkerOptions {
        count: 180,
        margin: 0.9,
    };
    let e = ScanTransferOptions::new(bad, 30.0).unwrap_err().to_string();
    assert!(e.contains("MarkerOptions::margin"), "{e}");
}
