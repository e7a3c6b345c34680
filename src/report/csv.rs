//! CSV tables: the cable table a manufacturer needs, and the design front.

use std::fmt::Write;

use crate::network::Network;
use crate::scene::Cables;
use crate::uniformity::{Design, FrontPoint};

/// `id,group,i,j,q,tension_n,length_m,cut_length_m`: one row per cable, with the
/// unstressed cut length `L0 = ℓ/(1 + T/EA)` (DESIGN §7).
///
/// # Panics
/// If `design` does not belong to `network`.
#[track_caller]
pub fn cables_csv(network: &Network, design: &Design, cables: &Cables) -> String {
    assert_eq!(
        design.q.len(),
        network.n_edges(),
        "design of another network"
    );
    let mut s = String::from("id,group,i,j,q,tension_n,length_m,cut_length_m\n");
    for (k, &[i, j]) in network.edges.iter().enumerate() {
        let (t, l) = (design.tensions_n[k], design.lengths_m[k]);
        let _ = writeln!(
            s,
            "{k},{},{i},{j},{:.12e},{:.12e},{:.12e},{:.12e}",
            network.group_of(k),
            design.q[k],
            t,
            l,
            cables.cut_length_m(l, t)
        );
    }
    s
}

/// `solver,knob,ratio,rms_mm,time_s`: the successful points of a design front.
pub fn front_csv(points: &[FrontPoint]) -> String {
    let mut s = String::from("solver,knob,ratio,rms_mm,time_s\n");
    for p in points.iter().filter(|p| p.outcome.is_ok()) {
        let name = clap::ValueEnum::to_possible_value(&p.solver)
            .map(|v| v.get_name().to_string())
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "{name},{:e},{:.10e},{:.6e},{:.6e}",
            p.knob, p.ratio, p.rms_mm, p.time_s
        );
    }
    s
}
