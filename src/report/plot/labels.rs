//! Point labels: their font, and where each goes beside its point without
//! overprinting another.

use plotters::prelude::*;

/// The font of point labels.
pub(super) fn label_font() -> TextStyle<'static> {
    ("sans-serif", LABEL_PX).into_font().into()
}

/// Height of a point label, px.
const LABEL_PX: i32 = 12;

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
            let width = 7 * label.chars().count() as i32;
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
