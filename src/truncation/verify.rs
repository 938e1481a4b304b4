//! A recording's located bifurcations re-solved at higher truncation orders (`replay
//! verify`, `tmrotor report --verify`): the recorded branch's points and bifurcations
//! handed to [`crate::sweep::verify::verify_events`], which the sweep itself runs after
//! its branch by default. The recorded order itself is a check of the method: every
//! bifurcation must be found again where it was.

use crate::model::Model;
use crate::record::TruncationCheck;
use crate::record::reader::Recording;
use crate::sweep::verify::{Event, StartPoint, verify_events};
use crate::sweep::{StudySettings, SweepError};

pub use crate::sweep::verify::VerifyOptions;

/// Re-solves the bifurcations of `rec`'s own branch at `options.orders`, telling
/// `progress` what it does; one check per bifurcation, in `/bifurcations` order.
pub fn verify_bifurcations(
    rec: &Recording,
    options: &VerifyOptions,
    progress: impl FnMut(&str) + Send,
) -> Result<Vec<TruncationCheck>, SweepError> {
    let settings = StudySettings::from_run(&rec.run)?;
    let model = Model::from_str(&rec.run.model_text, &rec.run.model_name)
        .map_err(|e| SweepError::Derive(format!("the recording's model: {e}")))?;
    let basis = rec.run.basis().ok();
    let events: Vec<Event> = rec
        .bifurcations
        .iter()
        .filter(|b| b.branch == 0)
        .map(|b| Event {
            number: b.number,
            kind: Some(b.kind),
            omega_rad_s: b.omega_rad_s,
            after_point: b.after_point,
        })
        .collect();
    let points: Vec<StartPoint> = rec
        .points
        .iter()
        .filter(|p| p.branch == 0)
        .map(|p| StartPoint {
            index: p.index,
            omega_rad_s: p.omega_rad_s,
            coeffs_mech: &p.coeffs_mech,
            coeffs_therm: &p.coeffs_therm,
        })
        .collect();
    verify_events(
        &settings,
        &model,
        basis.as_ref(),
        &points,
        &events,
        options,
        progress,
        &|| false,
    )
}
