//! Point labels: their font, and where each goes beside its point without
//! overprinting another.

use plotters::prelude::*;

/// The font of point labels.
pub(super) fn label_font() -> TextStyle<'static> {
    ("sans-serif", LABEL_PX).into_font().into()
}

/// Height of a point label, px.
const LABEL_PX: i32 = 12;

/// Width of a label as the shipped font draws it, px, with a pixel to
/// spare; 8 px a character should the font not measure it.
pub(super) fn label_width(label: &str) -> i32 {
    super::canvas::register_font();
    label_font()
        .font
        .box_size(label)
        .map_or(8 * label.chars().count() as i32, |(w, _)| w as i32 + 1)
}

/// Where to write each label beside its point (`anchors`: the point in
/// pixels and its label, if it has one), as a pixel offset from the point:
/// to the right or left, above or below, else stacked further down, at the
/// first place that overlaps no label already placed; `None` for a label
/// with no free place (left out rather than overprinted).
pub(super) fn place_labels(anchors: &[((i32, i32), Option<&str>)]) -> Vec<Option<(i32, i32)>> {
    let mut placed: Vec<[i32; 4]> = Vec::new();
    anchors
        .iter()
        .map(|&((x, y), label)| {
            let label = label?;
            let width = label_width(label);
            let h = LABEL_PX + 1;
            let candidates = [(7, -h), (7, 2), (-width - 7, -h), (-width - 7, 2)]
                .into_iter()
                .chain((1..=4).map(|k| (7, 2 + k * h)));
            let free = |(dx, dy): (i32, i32)| {
                let r = [x + dx, y + dy, x + dx + width, y + dy + h];
                !placed
                    .iter()
                    .any(|q| r[0] < q[2] && q[0] < r[2] && r[1] < q[3] && q[1] < r[3])
            };
            let (dx, dy) = candidates.into_iter().find(|&c| free(c))?;
            placed.push([x + dx, y + dy, x + dx + width, y + dy + h]);
            Some((dx, dy))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boxes [`place_labels`] gives: `[x0, y0, x1, y1]` per placed label.
    fn boxes(anchors: &[((i32, i32), Option<&str>)]) -> Vec<[i32; 4]> {
        anchors
            .iter()
            .zip(place_labels(anchors))
            .filter_map(|(&((x, y), label), offset)| {
                let (dx, dy) = offset?;
                let (x, y) = (x + dx, y + dy);
                Some([x, y, x + label_width(label?), y + LABEL_PX + 1])
            })
            .collect()
    }

    fn overlapping(boxes: &[[i32; 4]]) -> Option<([i32; 4], [i32; 4])> {
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[..i] {
                if a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3] {
                    return Some((*a, *b));
                }
            }
        }
        None
    }

    /// The labels of every committed front and study (their knob values and
    /// settings), crowded onto a few pixels the way a front's points pile up
    /// at the RMS floor: no two placed labels overlap, each as wide as the
    /// font draws it. (The figures themselves, every text as drawn, are
    /// checked in `label_check`.)
    #[test]
    fn crowded_labels_are_placed_apart_or_left_out() {
        let results = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("results");
        let mut sets = Vec::new();
        for scene in std::fs::read_dir(&results).unwrap() {
            let dir = scene.unwrap().path();
            for (file, column) in [("front.csv", "knob"), ("accuracy-vs-time.csv", "value")] {
                let Ok(text) = std::fs::read_to_string(dir.join(file)) else {
                    continue;
                };
                let mut lines = text.lines().filter(|l| !l.starts_with('#'));
                let header: Vec<&str> = lines.next().unwrap().split(',').collect();
                let k = header.iter().position(|h| *h == column).unwrap();
                let labels: Vec<String> = lines
                    .filter_map(|l| l.split(',').nth(k))
                    .filter(|v| !v.is_empty())
                    .map(|v| match v.parse::<f64>() {
                        Ok(x) if x != 0.0 => format!("{x:.0e}"),
                        _ => v.to_string(),
                    })
                    .collect();
                sets.push((dir.join(file), labels));
            }
        }
        assert!(sets.len() >= 3, "committed plots found: {sets:?}");
        for (file, labels) in sets {
            for spread in [0, 3, 12] {
                let anchors: Vec<((i32, i32), Option<&str>)> = labels
                    .iter()
                    .enumerate()
                    .map(|(i, l)| {
                        let i = i as i32;
                        (
                            (400 + spread * (i % 5), 300 + spread * (i / 5)),
                            Some(l.as_str()),
                        )
                    })
                    .collect();
                let placed = boxes(&anchors);
                assert!(
                    overlapping(&placed).is_none(),
                    "{}: labels overlap: {:?}",
                    file.display(),
                    overlapping(&placed)
                );
            }
        }
    }

    /// A label is measured by the shipped font (not the 8 px a character
    /// of the fallback): wider text, a wider box.
    #[test]
    fn a_label_is_as_wide_as_the_font_draws_it() {
        let w = label_width("1e-2");
        assert!((16..32).contains(&w), "{w}");
        assert!(label_width("0.0001") > label_width("1e-2"));
    }
}
