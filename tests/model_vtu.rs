//! `model.vtu`, the assembled model for ParaView (issue 37): its group names
//! readable as strings, each front node's deviation from the paraboloid and
//! each cable's cut length to colour by, read back from the file `design`
//! writes and checked against the design's own report and `cables.csv`.

mod common;

use ringmesh::design::DesignSettings;
use ringmesh::geometry::build_mesh;
use ringmesh::run::design;

/// The text of the `DataArray` called `name` inside the `<section>` element
/// (`FieldData`, `PointData`, `CellData`) of `vtu`, split into its words;
/// also the array's opening tag.
fn array<'a>(vtu: &'a str, section: &str, name: &str) -> (&'a str, Vec<&'a str>) {
    let body = vtu
        .split(&format!("<{section}>"))
        .nth(1)
        .and_then(|s| s.split(&format!("</{section}>")).next())
        .unwrap_or_else(|| panic!("no <{section}>"));
    let start = body
        .find(&format!("Name=\"{name}\""))
        .unwrap_or_else(|| panic!("no {section} array {name}"));
    let rest = &body[body[..start].rfind("<DataArray").unwrap()..];
    let (tag, rest) = rest.split_once('>').unwrap();
    let data = rest.split("</DataArray>").next().unwrap();
    (tag, data.split_whitespace().collect())
}

/// The numbers of an array.
fn numbers(words: &[&str]) -> Vec<f64> {
    words.iter().map(|w| w.parse().unwrap()).collect()
}

/// The strings of a VTK XML ASCII `String` array: each its bytes as
/// integers, ended by a 0.
fn strings(words: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    let mut bytes = Vec::new();
    for w in words {
        match w.parse::<u8>().unwrap() {
            0 => out.push(String::from_utf8(std::mem::take(&mut bytes)).unwrap()),
            b => bytes.push(b),
        }
    }
    assert!(bytes.is_empty(), "a string not ended by 0");
    out
}

/// An attribute of the `Piece` element.
fn piece(vtu: &str, attribute: &str) -> usize {
    let rest = vtu.split(&format!("{attribute}=\"")).nth(1).unwrap();
    rest[..rest.find('"').unwrap()].parse().unwrap()
}

/// small-hex designed and written: `model.vtu` holds the group names as a
/// field-data string array the integer `group` indexes, `deviation_mm` on
/// every point (the front net's free nodes deviating as the design's report
/// says — its node RMS and largest deviation recomputed from the file —,
/// every other node 0) and `cut_length_m` on every cell (the cables'
/// equal to `cables.csv`'s, the truss's 0).
#[test]
fn model_vtu_names_its_groups_and_carries_deviation_and_cut_lengths() {
    let out = tempfile::tempdir().unwrap();
    let scene = common::problem("small-hex.toml");
    let outcome = design(
        &scene,
        &DesignSettings::default(),
        Some(out.path()),
        &mut |_, _| {},
    )
    .unwrap();
    let v = &outcome.report.verification;
    let vtu = std::fs::read_to_string(out.path().join("model.vtu")).unwrap();
    let (n_points, n_cells) = (piece(&vtu, "NumberOfPoints"), piece(&vtu, "NumberOfCells"));
    let n_nodes = v.nodes_xyz_m.len();
    let n_cables = v.tensions_n.len();
    assert_eq!(n_points, n_nodes + 2 * v.truss_segments_m.len());
    assert_eq!(n_cells, n_cables + v.truss_segments_m.len());

    // cables.csv: id,group,i,j,q,tension_n,length_m,cut_length_m.
    let csv = std::fs::read_to_string(out.path().join("cables.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), n_cables);

    // Group names: a String array in field data, indexed by `group`.
    let (tag, words) = array(&vtu, "FieldData", "group_names");
    let names = strings(&words);
    assert!(tag.contains("type=\"String\""), "{tag}");
    assert!(
        tag.contains(&format!("NumberOfTuples=\"{}\"", names.len())),
        "{tag}"
    );
    let groups = numbers(&array(&vtu, "CellData", "group").1);
    assert_eq!(groups.len(), n_cells);
    let name_of = |k: usize| names[groups[k] as usize].as_str();
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(name_of(k), row[1], "cable {k}");
    }
    assert!((n_cables..n_cells).all(|k| name_of(k) == "truss"));
    assert!(names.len() >= 3, "{names:?}");

    // Deviation: the front net's free nodes as the report measures them.
    let deviation = numbers(&array(&vtu, "PointData", "deviation_mm").1);
    assert_eq!(deviation.len(), n_points);
    let fixed = numbers(&array(&vtu, "PointData", "fixed").1);
    let mesh = build_mesh(&common::scene("small-hex")).unwrap();
    let free_front: Vec<f64> = (0..mesh.n_front_nodes)
        .filter(|&i| fixed[i] == 0.0)
        .map(|i| deviation[i])
        .collect();
    assert!(!free_front.is_empty());
    let largest = free_front.iter().map(|d| d.abs()).fold(0.0, f64::max);
    let rms = (free_front.iter().map(|d| d * d).sum::<f64>() / free_front.len() as f64).sqrt();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
    assert!(
        close(largest, v.max_deviation_mm),
        "{largest} mm, report {} mm",
        v.max_deviation_mm
    );
    assert!(close(rms, v.rms_mm), "{rms} mm, report {} mm", v.rms_mm);
    // ~0 to the design's accuracy: the loop's tolerance is 1e-6 m = 1e-3 mm.
    assert!(largest <= 1e-3, "{largest} mm");
    assert!(deviation[mesh.n_front_nodes..].iter().all(|&d| d == 0.0));

    // Cut lengths: cables.csv's for the cables, 0 for the truss.
    let cut = numbers(&array(&vtu, "CellData", "cut_length_m").1);
    assert_eq!(cut.len(), n_cells);
    for (k, row) in rows.iter().enumerate() {
        let csv_cut: f64 = row[7].parse().unwrap();
        assert!(
            (cut[k] - csv_cut).abs() <= 1e-12 * csv_cut,
            "cable {k}: {} m in model.vtu, {csv_cut} m in cables.csv",
            cut[k]
        );
        assert!(cut[k] > 0.0);
    }
    assert!(cut[n_cables..].iter().all(|&c| c == 0.0));
}
