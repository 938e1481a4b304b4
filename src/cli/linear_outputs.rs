//! Outputs of the linear analyses: their figures drawn in the formats a command asks for
//! (the figures themselves are [`crate::figure::linear`]'s) and their tables as CSV.

use std::fmt::Write as _;

use crate::figure::Figure;
use crate::linear::{Campbell, Mode, NodeOrbit, UnbalanceResponse, forward_share};

/// Draws `fig` to `stem` in the formats of `args`; returns the files written.
pub fn draw(
    stem: &std::path::Path,
    fig: &Figure,
    args: &super::FigureArgs,
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    use anyhow::Context;
    let written = crate::figure::write_figure(stem, fig, &args.output()?)
        .with_context(|| format!("drawing {}", stem.display()))?;
    Ok(written.files)
}

/// The Campbell diagram as CSV: one row per speed and followed mode.
pub fn campbell_csv(c: &Campbell) -> String {
    let mut text = String::from(
        "speed_rad_s,mode,frequency_rad_s,frequency_hz,damping_ratio,log_decrement,whirl,forward_share,mac\n",
    );
    for p in &c.points {
        for (i, m) in p.modes.iter().enumerate() {
            let _ = writeln!(
                text,
                "{},{},{},{},{},{},{},{},{}",
                p.speed_rad_s,
                i + 1,
                m.frequency_rad_s,
                m.frequency_rad_s / (2.0 * std::f64::consts::PI),
                m.damping_ratio,
                m.log_decrement,
                m.whirl,
                m.forward_share,
                m.mac
            );
        }
    }
    text
}

/// Mode shapes as CSV: per mode and node, the complex amplitudes of x, y, θx, θy (the
/// mode's largest entry is 1), the orbit's semi-axes and its whirl.
pub fn shapes_csv(modes: &[Mode], node_ids: &[u32], axial_m: &[f64]) -> String {
    let mut text = String::from(
        "mode,frequency_rad_s,whirl,forward_share,node,axial_m,x_re,x_im,y_re,y_im,\
         theta_x_re,theta_x_im,theta_y_re,theta_y_im,major_axis,minor_axis,node_whirl\n",
    );
    for (k, m) in modes.iter().enumerate() {
        for (i, id) in node_ids.iter().enumerate() {
            let d = &m.shape[4 * i..4 * i + 4];
            let orbit = NodeOrbit { x: d[0], y: d[1] };
            let _ = writeln!(
                text,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                k + 1,
                m.frequency_rad_s,
                m.whirl,
                forward_share(&m.shape),
                id,
                axial_m[i],
                d[0].re,
                d[0].im,
                d[1].re,
                d[1].im,
                d[2].re,
                d[2].im,
                d[3].re,
                d[3].im,
                orbit.major_axis(),
                orbit.minor_axis(),
                if orbit.forward() {
                    "forward"
                } else {
                    "backward"
                }
            );
        }
    }
    text
}

/// The unbalance response as CSV: one row per speed, exciting rotor and node.
pub fn unbalance_csv(resp: &[UnbalanceResponse], node_ids: &[u32]) -> String {
    let mut text = String::from(
        "speed_rad_s,rotor,frequency_rad_s,node,x_amplitude_m,x_phase_deg,y_amplitude_m,\
         y_phase_deg,major_axis_m,minor_axis_m,whirl\n",
    );
    for r in resp {
        for (i, id) in node_ids.iter().enumerate() {
            let o = r.node(i);
            let _ = writeln!(
                text,
                "{},{},{},{},{},{},{},{},{},{},{}",
                r.speed_rad_s,
                r.rotor_id,
                r.frequency_rad_s,
                id,
                o.x.norm(),
                o.x.arg().to_degrees(),
                o.y.norm(),
                o.y.arg().to_degrees(),
                o.major_axis(),
                o.minor_axis(),
                if o.forward() { "forward" } else { "backward" }
            );
        }
    }
    text
}
