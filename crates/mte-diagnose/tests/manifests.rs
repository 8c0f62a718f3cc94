//! Manifests: the instrument is picked from `format` and `kind`, unknown fields are errors, a
//! UTF-8 byte-order mark is accepted, and messages name the file and the field.

mod common;
use std::path::PathBuf;

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/datasets/x-axis-runs")
}

/// Writes `manifest` beside a copy of the bundled axis runs and loads it.
fn load_with(name: &str, manifest: &[u8]) -> Result<mte_diagnose::Prepared, String> {
    let dir = common::scratch(&format!("manifests-{name}"));
    std::fs::copy(fixture().join("runs.csv"), dir.join("runs.csv")).unwrap();
    std::fs::write(dir.join("manifest.json"), manifest).unwrap();
    mte_diagnose::load(&dir.join("manifest.json")).map_err(|e| e.to_string())
}

#[test]
fn a_kind_no_instrument_has_lists_the_kinds() {
    let err = load_with(
        "kind",
        br#"{"format": "mte-dataset/1", "kind": "point", "data": "runs.csv"}"#,
    )
    .err()
    .unwrap();
    assert!(
        err.contains("manifest.json")
            && err.contains("`point`")
            && err.contains("axis, tracker, points"),
        "{err}"
    );
}

#[test]
fn an_unknown_field_is_an_error_naming_it() {
    let err = load_with(
        "unknown",
        br#"{"format": "mte-dataset/1", "kind": "axis", "axis": "X", "data": "runs.csv", "noise_um": 0.3, "noise_unit": "um"}"#,
    )
    .err()
    .unwrap();
    assert!(
        err.contains("manifest.json") && err.contains("noise_unit"),
        "{err}"
    );
}

#[test]
fn a_byte_order_mark_is_accepted() {
    let mut text = b"\xEF\xBB\xBF".to_vec();
    text.extend_from_slice(
        br#"{"format": "mte-dataset/1", "kind": "axis", "axis": "X", "data": "runs.csv", "noise_um": 0.3}"#,
    );
    let p = load_with("bom", &text).unwrap();
    assert!(p.observations.len() > 100);
}

#[test]
fn a_missing_format_says_which_are_read() {
    let err = load_with("format", br#"{"kind": "axis", "data": "runs.csv"}"#)
        .err()
        .unwrap();
    assert!(
        err.contains("field `format`: missing") && err.contains("mte-rtest/1"),
        "{err}"
    );
}

/// An absurd coordinate in 3-D points is an input error naming line and column (it used to
/// send the pose fit's SVD into an endless loop).
#[test]
fn an_absurd_point_is_an_error_not_a_hang() {
    let src =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/datasets/c-stage-points");
    let dir = common::scratch("manifests-points");
    for f in ["manifest.json", "machine.json"] {
        std::fs::copy(src.join(f), dir.join(f)).unwrap();
    }
    let csv = std::fs::read_to_string(src.join("points.csv")).unwrap();
    let mut lines: Vec<String> = csv.lines().map(String::from).collect();
    let mut fields: Vec<String> = lines[3].split(',').map(String::from).collect();
    let last = fields.len() - 1;
    fields[last] = "1e300".into();
    lines[3] = fields.join(",");
    std::fs::write(dir.join("points.csv"), lines.join("\n")).unwrap();
    let err = mte_diagnose::load(&dir.join("manifest.json"))
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("points.csv") && err.contains("line 4") && err.contains("point_z_mm"),
        "{err}"
    );
}

#[test]
fn a_noise_given_that_is_not_positive_is_an_error_naming_it() {
    let manifest = fixture().join("manifest.json");
    for bad in [-0.5, 0.0, f64::NAN] {
        let err = mte_diagnose::load_with_noise(&manifest, Some(bad))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            err.contains("--noise-um") && err.contains("positive"),
            "{bad}: {err}"
        );
    }
    assert!(mte_diagnose::load_with_noise(&manifest, Some(0.5)).is_ok());
}
