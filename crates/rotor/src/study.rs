//! A study: the settings of one sweep, and the problem they build (the coupled rotor, the
//! harmonic basis, the run description and the stability method).
//!
//! This is the layer between the physics ([`crate::coupled`], [`crate::model`]) and its
//! users: the sweep driver (`sweep`), the re-derivation of recorded points (`derive`)
//! and the truncation study all build their problem here, so that a
//! recording's embedded settings rebuild exactly the problem that made it.
//!
//! Defaults (the paper's default study, section 5): q_l = 2 L/min, cooling and ambient
//! 25 °C, ω from 300 to 700 rad/s, truncation order 3 (paper Eq. 34 with λ = 6/5 from the
//! model's rotor speed ratios); the reasons for the numerical defaults are on each field.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::coupled::{CoupledError, CoupledRotor, CouplingOptions, StudyOverrides};
use crate::hb::{Basis, Ratio};
use crate::model::{Dir, Model, ModelSet};
use crate::record::types::{BearingInfo, DynamicNode, RunInfo, ThermalNode};
use crate::stability::{
    CraigBampton, ExpSip, IntervalMap, Reduced, ReductionSettings, Sip, StabilityError,
    StabilityMethod,
};

/// Errors building a study's problem: the model, the coupled system, the basis or a
/// setting.
#[derive(Debug, Error)]
pub enum StudyError {
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    #[error(transparent)]
    Coupled(#[from] CoupledError),
    #[error(transparent)]
    Basis(#[from] crate::hb::BasisError),
    #[error(
        "study setting {field}{} = {value}: {reason}",
        crate::input::flag_note(field)
    )]
    Setting {
        field: &'static str,
        value: String,
        reason: &'static str,
    },
}

/// Samples per period used for the recorded orbits, bearing loads and temperature ranges.
pub const RECORD_SAMPLES: usize = 128;

/// Everything a sweep needs besides the model file, grouped by the layer that uses it:
/// the operating point of the coupled model, the harmonic basis, the continuation in ω
/// and the Floquet stability. Every default is the paper's default study (see the module
/// docs).
///
/// In files (a study's settings TOML, a campaign's `[defaults]` and runs, the settings a
/// recording embeds) the settings are one flat table, e.g. `flow_l_min = 2.0` and
/// `order = 3`, as they have always been; [`FlatSettings`] is that form.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "FlatSettings", into = "FlatSettings")]
pub struct StudySettings {
    /// Model file; `None` is the built-in dual rotor.
    pub model: Option<PathBuf>,
    /// The operating point of the coupled model.
    pub operating: OperatingSettings,
    /// The harmonic-balance basis and its time grid.
    pub harmonic: HarmonicSettings,
    /// The continuation in rotor speed.
    pub sweep: SweepSettings,
    /// Floquet multipliers and the bifurcations found from them.
    pub floquet: FloquetSettings,
    /// Values of the model file set by path before it is validated (`[set]` in a
    /// campaign, `--set PATH=VALUE` on the command line; see [`crate::model::set`]), e.g.
    /// `"thermal.bearings[2#].f_v" = 3.0`. Empty by default; absent from the settings TOML
    /// when empty.
    pub set: ModelSet,
}

/// The operating point of the coupled model (paper section 5; used by
/// [`crate::coupled::CoupledRotor`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OperatingSettings {
    /// Lubricant flow rate per bearing `q_l` (L/min). Default 2, the paper's default study.
    pub flow_l_min: f64,
    /// Lubricant cooling temperature `T_L∞` (°C). Default 25 (section 5).
    pub cooling_temp_c: f64,
    /// Ambient temperature `T_∞` (°C). Default 25 (section 5).
    pub ambient_temp_c: f64,
    /// Solve the thermal network together with the vibration (two-way coupling). Default
    /// on.
    pub thermal: bool,
}

impl Default for OperatingSettings {
    fn default() -> Self {
        Self {
            flow_l_min: 2.0,
            cooling_temp_c: 25.0,
            ambient_temp_c: 25.0,
            thermal: true,
        }
    }
}

/// The harmonic-balance basis ([`crate::hb`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HarmonicSettings {
    /// Truncation order `k` of the basis (Eq. 34). Default 3: the paper's order, and
    /// converged on the default study (`docs/validation.md`, truncation).
    pub order: u32,
    /// AFT samples per period; `None` (default) chooses from the basis.
    pub aft_samples: Option<usize>,
    /// Keep the half orders of the paper's basis that the rotors' speeds cannot make
    /// (`ω/2` for λ = 6/5: Eq. 34 has it, but no combination of `ω` and `λω` gives it).
    /// Default true, the paper's basis. False follows the primary response, which has
    /// none of them, on its own (shorter) period: its period doublings are then located as
    /// such (a multiplier through −1) and the branch cannot drift into the period-doubled
    /// response (see [`primary_basis`]).
    pub half_orders: bool,
    /// Add the combination tones of the two rotors' speeds (`(λ − 1)ω = ω/5`, `4ω/5`,
    /// `(1 + λ)ω = 11ω/5`, … for λ = 6/5): every multiple of `ω/den(λ)` up to the basis's
    /// highest harmonic ([`combination_basis`]). Default false, the paper's basis (Eq. 34),
    /// which has none of them; the nonlinear bearings make them, and near a resonance they
    /// change the response (docs/transient.md: the time response against the balance).
    pub combination_tones: bool,
    /// Integrate every rolling element's contact between the instants where it takes up
    /// and loses its load ([`CouplingOptions::exact_contacts`]). Default false (the AFT's
    /// samples, several times cheaper); true where elements lose contact and sampling
    /// makes or moves folds.
    pub exact_contacts: bool,
}

impl Default for HarmonicSettings {
    fn default() -> Self {
        Self {
            order: 3,
            aft_samples: None,
            half_orders: true,
            combination_tones: false,
            exact_contacts: false,
        }
    }
}

/// The continuation in rotor speed ([`crate::continuation`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepSettings {
    /// Sweep start (rad/s). Default 300, the paper's range.
    pub omega_start: f64,
    /// Sweep end (rad/s). Default 700.
    pub omega_end: f64,
    /// Largest continuation step (scaled arclength; see `continuation::ContinuationOptions`).
    ///
    /// Default 0.15. Why: on the default study, 0.05, 0.10 and 0.15 give the same
    /// ω-turning points (to 0.1 rad/s, the 0.05 run adds one pair of tiny zigzags) and the
    /// same node-8 peaks (to 0.2 rad/s and 0.01 µm), with 958, 460 and 314 points; the
    /// step control shortens the step where the branch bends, so the cap mostly sets
    /// the spacing on the flat parts.
    pub ds_max: f64,
    /// Maximum number of points. Default 2000, far above the 150–500 points a sweep of the
    /// paper's range takes: a guard against a branch that never reaches the end.
    pub max_points: usize,
    /// Follow the period-doubled branch from every period doubling the sweep locates,
    /// each recorded as a branch of its own beside the run's (branch 1, 2, …; see
    /// `SweepProblem::run`). Default true. It takes effect on a primary basis
    /// (`half_orders = false`, or a single rotor's integer basis, which has no half
    /// orders either way) with stability on: there a period doubling is located as
    /// such, and its branch needs the half orders the basis lacks. On the paper's basis the
    /// half orders are already in; a period doubling there would need quarter orders, a
    /// basis three times as large, and is left to the user.
    pub switch_branches: bool,
}

impl Default for SweepSettings {
    fn default() -> Self {
        Self {
            omega_start: 300.0,
            omega_end: 700.0,
            ds_max: 0.15,
            max_points: 2000,
            switch_branches: true,
        }
    }
}

/// Floquet stability ([`crate::stability`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FloquetSettings {
    /// Compute Floquet multipliers at every point (and locate the Neimark–Sacker and
    /// period-doubling points; saddle-nodes, the folds of the branch, are located either
    /// way). Default on.
    pub stability: bool,
    /// Floquet method (see [`StabilityChoice`]). Default `exp-sip`.
    pub stability_method: StabilityChoice,
    /// Intervals per period of the SIP product (Eq. 33), default 512. `exp-sip`: the fine
    /// product of the extrapolation (even), the start of the refinement near the unit
    /// circle (doubled up to 4096); the explicit `sip` method raises it automatically for
    /// stiff systems.
    pub sip_intervals: usize,
    /// Interval map of the `exp-sip` product: `exponential` (default) or `strang`, the
    /// map of earlier versions (see [`IntervalMap`]). Recordings whose embedded settings
    /// lack this field were made with `strang`, and are re-derived with it.
    pub interval_map: IntervalMap,
    /// Cut-off (rad/s) of the Craig–Bampton reduction the stability is computed on
    /// (interior modes of the rotor with its bearing DoFs held, up to this frequency);
    /// 0 computes on the full model. Default: [`ReductionSettings::default`].
    pub reduction_cutoff_rad_s: f64,
    /// After the branch, re-solve each located bifurcation and each change of stability the
    /// sweep could not locate at higher truncation orders and record whether it holds,
    /// moves or vanishes (`/truncation`, the sweep's `verify` module). Default on; needs
    /// `stability`.
    pub verify: bool,
    /// The orders of that check; empty (the default): the run's order + 1 and + 2, at
    /// most 12.
    pub verify_orders: Vec<u32>,
    /// Wall-time budget of the check, s (default 120): windows not reached in it are
    /// reported unchecked, so a sweep with many bifurcations still ends.
    pub verify_max_seconds: f64,
}

/// Default of [`FloquetSettings::verify_max_seconds`]: two minutes, about twenty windows
/// of the dual rotor at two orders.
pub const DEFAULT_VERIFY_SECONDS: f64 = 120.0;

impl FloquetSettings {
    /// The orders the truncation check re-solves at for a run of order `order`:
    /// [`Self::verify_orders`], or `order + 1` and `order + 2` up to 12.
    pub fn verify_orders_for(&self, order: u32) -> Vec<u32> {
        if self.verify_orders.is_empty() {
            (order + 1..=order + 2).filter(|&k| k <= 12).collect()
        } else {
            self.verify_orders.clone()
        }
    }
}

impl Default for FloquetSettings {
    fn default() -> Self {
        Self {
            stability: true,
            stability_method: StabilityChoice::ExpSip,
            sip_intervals: DEFAULT_INTERVALS,
            interval_map: IntervalMap::Exponential,
            reduction_cutoff_rad_s: ReductionSettings::default().cutoff_rad_s,
            verify: true,
            verify_orders: Vec::new(),
            verify_max_seconds: DEFAULT_VERIFY_SECONDS,
        }
    }
}

/// The flat file form of [`StudySettings`] from one list: each setting once, as
/// `group.field: type`, in the order files write them. It generates [`FlatSettings`] and
/// both conversions, so a new setting is its field in its group (with its doc and
/// default) and one line here; `tests::every_grouped_setting_has_a_flat_key` fails on a
/// group field left out.
macro_rules! flat_settings {
    ($($group:ident . $field:ident : $ty:ty),* $(,)?) => {
        /// [`StudySettings`] as files spell them: one flat table, unknown keys refused,
        /// absent keys at their defaults. The field meanings are those of the grouped
        /// settings.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(deny_unknown_fields, default)]
        pub struct FlatSettings {
            pub model: Option<PathBuf>,
            $(pub $field: $ty,)*
            #[serde(skip_serializing_if = "ModelSet::is_empty")]
            pub set: ModelSet,
        }

        impl From<StudySettings> for FlatSettings {
            fn from(s: StudySettings) -> Self {
                Self {
                    model: s.model,
                    $($field: s.$group.$field,)*
                    set: s.set,
                }
            }
        }

        impl From<FlatSettings> for StudySettings {
            fn from(f: FlatSettings) -> Self {
                let mut s = StudySettings {
                    model: f.model,
                    set: f.set,
                    ..StudySettings::default()
                };
                $(s.$group.$field = f.$field;)*
                s
            }
        }

        /// The flat keys, in file order (without `model` and `set`).
        pub const FLAT_KEYS: &[&str] = &[$(stringify!($field)),*];
    };
}

flat_settings! {
    operating.flow_l_min: f64,
    operating.cooling_temp_c: f64,
    operating.ambient_temp_c: f64,
    harmonic.order: u32,
    sweep.omega_start: f64,
    sweep.omega_end: f64,
    sweep.ds_max: f64,
    sweep.max_points: usize,
    sweep.switch_branches: bool,
    operating.thermal: bool,
    floquet.stability: bool,
    floquet.stability_method: StabilityChoice,
    floquet.sip_intervals: usize,
    floquet.interval_map: IntervalMap,
    floquet.reduction_cutoff_rad_s: f64,
    harmonic.aft_samples: Option<usize>,
    harmonic.half_orders: bool,
    harmonic.combination_tones: bool,
    harmonic.exact_contacts: bool,
    floquet.verify: bool,
    floquet.verify_orders: Vec<u32>,
    floquet.verify_max_seconds: f64,
}

impl Default for FlatSettings {
    fn default() -> Self {
        StudySettings::default().into()
    }
}

impl StudySettings {
    /// The settings a recording was made with, from its embedded settings TOML, as this
    /// version reads them: settings embedded before the interval map was a setting get
    /// Strang's map (the only one then); the model path is dropped (the recording embeds the
    /// model itself).
    pub fn from_run(run: &RunInfo) -> Result<Self, StudyError> {
        let table: toml::Table = run.settings_toml.parse().map_err(|_| StudyError::Setting {
            field: "settings_toml",
            value: "(embedded)".into(),
            reason: "unreadable",
        })?;
        let mut settings = Self::from_table(&table)?;
        if !table.contains_key("interval_map") {
            settings.floquet.interval_map = IntervalMap::Strang;
        }
        settings.model = None;
        Ok(settings)
    }

    /// Settings from a TOML table (a study file's, a campaign manifest's); absent keys take
    /// their defaults.
    pub fn from_table(table: &toml::Table) -> Result<Self, StudyError> {
        toml::Value::Table(table.clone())
            .try_into()
            .map_err(|_| StudyError::Setting {
                field: "settings",
                value: "(table)".into(),
                reason: "not readable by this version",
            })
    }

    /// The values set on the model file as `path=value` parts joined by `, ` (empty when
    /// none): how figures and reports label a run of a parameter study.
    pub fn set_summary(&self) -> String {
        self.set
            .iter()
            .map(|(path, value)| format!("{path}={}", value_text(value)))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The settings as (key, value) pairs for a recording's metadata, in the order and
    /// spelling of their TOML form (generated from it, so a new setting appears without a
    /// list to keep), plus `model` (`built-in` or the file's path).
    pub fn key_values(&self) -> Vec<(String, String)> {
        let mut kv: Vec<(String, String)> = toml::Table::try_from(self)
            .unwrap_or_default()
            .into_iter()
            .filter(|(k, _)| k != "model" && k != "set")
            .map(|(k, v)| (k, value_text(&v)))
            .collect();
        for (path, value) in &self.set {
            kv.push((format!("set.{path}"), value_text(value)));
        }
        kv.push((
            "model".to_string(),
            self.model
                .as_ref()
                .map_or("built-in".to_string(), |p| p.display().to_string()),
        ));
        kv
    }
}

/// Default SIP intervals per period of a sweep: [`ExpSip`]'s default, 512 extrapolated
/// with 256 and refined up to 4096 intervals near the unit circle (the reason, with the
/// measured errors, is on [`ExpSip::default`]).
pub const DEFAULT_INTERVALS: usize = 512;

/// A TOML value as a person reads it: a string without quotes, anything else as TOML.
fn value_text(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Largest `sip_intervals` a study accepts (the explicit product's own automatic limit).
pub const MAX_SIP_INTERVALS: usize = 200_000;

/// A setting's value from its name in settings files (its serde name), so that the
/// command line accepts exactly the names the files do, from one list: the enum's
/// variants. The error lists the accepted names.
pub fn parse_name<T: serde::de::DeserializeOwned>(name: &str) -> Result<T, String> {
    use serde::de::value::{Error, StrDeserializer};
    T::deserialize(StrDeserializer::<Error>::new(name)).map_err(|e| e.to_string())
}

/// Which Floquet method a sweep uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StabilityChoice {
    /// Exponential-split SIP ([`ExpSip`]): the orbit-mean state matrix taken exactly, the
    /// fluctuation through the exponential interval map; works for stiff finite-element
    /// models. Default.
    ExpSip,
    /// The paper's explicit SIP product ([`Sip`], Eq. 33), with the interval count raised
    /// until `Δ·ρ(B) ≤ 1`; refuses models that would need more than 200 000 intervals.
    Sip,
}

impl StabilityChoice {
    /// Name used in settings files and on the command line.
    pub fn label(self) -> &'static str {
        match self {
            Self::ExpSip => "exp-sip",
            Self::Sip => "sip",
        }
    }
}

/// The stability method of `settings` for `system`: the chosen product, on a
/// Craig–Bampton reduction built at `omega_ref` unless the cut-off is 0.
pub fn stability_method(
    settings: &StudySettings,
    system: &CoupledRotor,
    omega_ref: f64,
) -> Result<Box<dyn StabilityMethod>, StabilityError> {
    let exp = ExpSip {
        intervals: settings.floquet.sip_intervals,
        interval_map: settings.floquet.interval_map,
        ..ExpSip::default()
    };
    let sip = Sip {
        intervals: settings.floquet.sip_intervals,
        ..Sip::default()
    };
    if settings.floquet.reduction_cutoff_rad_s == 0.0 {
        return Ok(match settings.floquet.stability_method {
            StabilityChoice::ExpSip => Box::new(exp),
            StabilityChoice::Sip => Box::new(sip),
        });
    }
    let reduction = CraigBampton::new(
        system,
        omega_ref,
        ReductionSettings {
            cutoff_rad_s: settings.floquet.reduction_cutoff_rad_s,
            max_modes: usize::MAX,
        },
    )?;
    Ok(match settings.floquet.stability_method {
        StabilityChoice::ExpSip => Box::new(Reduced {
            reduction,
            method: exp,
        }),
        StabilityChoice::Sip => Box::new(Reduced {
            reduction,
            method: sip,
        }),
    })
}

/// A built sweep problem: model, coupled system, basis and the run description.
pub struct SweepProblem {
    pub settings: StudySettings,
    pub model: Model,
    pub system: CoupledRotor,
    pub basis: Basis,
    pub run: RunInfo,
}

impl SweepProblem {
    /// Builds the problem from settings: reads the model file if one is given (else the
    /// built-in one) and applies the settings' `set` values to it.
    pub fn new(settings: &StudySettings) -> Result<Self, StudyError> {
        let model = Model::load(settings.model.as_deref(), &settings.set)?;
        Self::with_model(settings, model)
    }

    /// Builds the problem for an already parsed model, taken as it is (the settings'
    /// `set` values are not applied again: a recording embeds the edited model).
    pub fn with_model(settings: &StudySettings, model: Model) -> Result<Self, StudyError> {
        check_settings(settings)?;
        let study = StudyOverrides {
            flow_l_min: Some(settings.operating.flow_l_min),
            cooling_temp_c: Some(settings.operating.cooling_temp_c),
            ambient_temp_c: Some(settings.operating.ambient_temp_c),
        };
        let system = CoupledRotor::new(
            &model,
            &study,
            CouplingOptions {
                thermal: settings.operating.thermal,
                frozen_clearance: false,
                exact_contacts: settings.harmonic.exact_contacts,
            },
        )?;
        let lambda = speed_ratio(&model);
        let basis = if lambda == (Ratio { num: 1, den: 1 }) {
            Basis::integer(settings.harmonic.order)?
        } else if settings.harmonic.combination_tones {
            combination_basis(
                settings.harmonic.order,
                lambda,
                settings.harmonic.half_orders,
            )?
        } else if settings.harmonic.half_orders {
            Basis::paper(settings.harmonic.order, lambda)?
        } else {
            primary_basis(settings.harmonic.order, lambda)?
        };
        let run = run_info(&model, &system, &basis, lambda, settings);
        Ok(Self {
            settings: settings.clone(),
            model,
            system,
            basis,
            run,
        })
    }
}

/// A refused setting.
fn bad(field: &'static str, value: impl ToString, reason: &'static str) -> Result<(), StudyError> {
    Err(StudyError::Setting {
        field,
        value: value.to_string(),
        reason,
    })
}

/// Checks every group; the first refused setting is the error.
fn check_settings(s: &StudySettings) -> Result<(), StudyError> {
    s.sweep.check()?;
    s.harmonic.check()?;
    s.floquet.check()
}

impl SweepSettings {
    /// Refuses a non-positive or empty speed range, step or point budget.
    pub fn check(&self) -> Result<(), StudyError> {
        if !(self.omega_start.is_finite() && self.omega_start > 0.0) {
            return bad("omega_start", self.omega_start, "must be positive (rad/s)");
        }
        if !(self.omega_end.is_finite()
            && self.omega_end > 0.0
            && self.omega_end != self.omega_start)
        {
            return bad(
                "omega_end",
                self.omega_end,
                "must be positive and differ from omega_start",
            );
        }
        let ds_min = crate::continuation::ContinuationOptions::new(0.0, 1.0).ds_min;
        if !(self.ds_max.is_finite() && self.ds_max >= ds_min && self.ds_max <= 10.0) {
            return bad(
                "ds_max",
                self.ds_max,
                "must lie in [1e-7, 10] (the continuation's smallest step, and a step that crosses a branch's features unseen)",
            );
        }
        if self.max_points == 0 {
            return bad("max_points", 0, "must be at least 1");
        }
        Ok(())
    }
}

impl HarmonicSettings {
    /// Refuses an order outside 1–12.
    pub fn check(&self) -> Result<(), StudyError> {
        if self.order == 0 || self.order > 12 {
            return bad("order", self.order, "must be between 1 and 12");
        }
        Ok(())
    }
}

impl FloquetSettings {
    /// Refuses a negative cut-off and interval counts the products cannot use.
    pub fn check(&self) -> Result<(), StudyError> {
        if !(self.reduction_cutoff_rad_s.is_finite() && self.reduction_cutoff_rad_s >= 0.0) {
            return bad(
                "reduction_cutoff_rad_s",
                self.reduction_cutoff_rad_s,
                "must be 0 (full model) or a positive frequency in rad/s",
            );
        }
        if self.sip_intervals > MAX_SIP_INTERVALS {
            return bad(
                "sip_intervals",
                self.sip_intervals,
                "must be at most 200000 (the product keeps a state per interval; more would \
                 need gigabytes of memory, and 4096 already resolves the paper's rotor)",
            );
        }
        if self.sip_intervals < 8 {
            return bad("sip_intervals", self.sip_intervals, "must be at least 8");
        }
        if self.stability_method == StabilityChoice::ExpSip && !self.sip_intervals.is_multiple_of(2)
        {
            return bad(
                "sip_intervals",
                self.sip_intervals,
                "must be even for exp-sip (its product is extrapolated from N and N/2 intervals)",
            );
        }
        if let Some(k) = self.verify_orders.iter().find(|&&k| k == 0 || k > 12) {
            return bad("verify_orders", k, "must be truncation orders from 1 to 12");
        }
        if !(self.verify_max_seconds.is_finite() && self.verify_max_seconds > 0.0) {
            return bad(
                "verify_max_seconds",
                self.verify_max_seconds,
                "must be a positive number of seconds",
            );
        }
        Ok(())
    }
}

/// The paper's basis at `order` with every combination tone of the two speeds added: all
/// multiples of `ω/den(λ)` up to its highest harmonic (with `half_orders`, also the half
/// orders of Eq. 34: multiples of `ω/(2 den(λ))` where Eq. 34 has them).
pub fn combination_basis(
    order: u32,
    lambda: Ratio,
    half_orders: bool,
) -> Result<Basis, crate::hb::BasisError> {
    let paper = Basis::paper(order, lambda)?;
    let top = paper
        .harmonics()
        .iter()
        .map(|h| h.value())
        .fold(0.0f64, f64::max);
    let den = lambda.den;
    let mut list: Vec<Ratio> = Vec::new();
    let mut m = 1;
    while f64::from(m) / f64::from(den) <= top + 1e-12 {
        list.push(Ratio::new(m, den)?);
        m += 1;
    }
    if half_orders {
        for h in paper.harmonics() {
            if !list.contains(h) {
                list.push(*h);
            }
        }
    }
    list.sort_by(|a, b| a.value().total_cmp(&b.value()));
    Basis::new(list)
}

/// The paper's basis (Eq. 34) without the harmonics that no combination `aω + bλω` of
/// the rotor speeds makes: with `λ = p/q` those combinations are the multiples of `ω/q`,
/// so for λ = 6/5 `ω/2` goes and `λω/2 = 3ω/5` stays. The unbalance response and every
/// harmonic its nonlinear forces generate lie on that lattice (the primary response); a
/// period doubling of it brings in the odd multiples of `ω/(2q)`, `ω/2` among them. On
/// the primary basis the response's period is `2πq/ω` instead of `4πq/ω`.
pub fn primary_basis(order: u32, lambda: Ratio) -> Result<Basis, crate::hb::BasisError> {
    let paper = Basis::paper(order, lambda)?;
    let on_lattice = |h: &Ratio| (h.num * lambda.den).is_multiple_of(h.den);
    Basis::new(
        paper
            .harmonics()
            .iter()
            .copied()
            .filter(on_lattice)
            .collect(),
    )
}

/// λ of the basis (Eq. 34): the speed of the second spinning rotor, `|ratio|` (1 for a
/// single rotor). The basis holds frequencies, so a counter-rotating rotor's `−6/5` needs
/// the same `6/5 ω` harmonics as a co-rotating one's; a part that does not spin adds none.
/// Ratios are rational by model validation.
pub fn speed_ratio(model: &Model) -> Ratio {
    let one = Ratio { num: 1, den: 1 };
    model
        .speed_ratios()
        .iter()
        .filter_map(|r| r.magnitude)
        .find(|r| *r != one)
        .unwrap_or(one)
}

fn run_info(
    model: &Model,
    system: &CoupledRotor,
    basis: &Basis,
    lambda: Ratio,
    settings: &StudySettings,
) -> RunInfo {
    let axial = model.axial_positions();
    let nodes = model
        .node_ids()
        .iter()
        .enumerate()
        .map(|(i, &id)| DynamicNode {
            id,
            name: format!("node {id}"),
            dof_x: model.dof(id, Dir::X).unwrap_or(0),
            dof_y: model.dof(id, Dir::Y).unwrap_or(0),
            axial_position_m: axial[i],
            rotor: model.spec.rotors[model.rotor_of(i)].id.clone(),
        })
        .collect();
    let thermal_nodes = system
        .network()
        .map(|net| {
            net.names()
                .iter()
                .enumerate()
                .map(|(p, name)| ThermalNode {
                    id: (p + 1) as u32,
                    name: name.clone(),
                    dof: p,
                })
                .collect()
        })
        .unwrap_or_default();
    let bearings = system
        .bearing_ids()
        .iter()
        .zip(system.initial_clearances_m())
        .map(|(name, d0)| BearingInfo {
            name: name.to_string(),
            initial_clearance_m: d0,
        })
        .collect();
    let settings_toml = toml::to_string(settings).unwrap_or_default();
    let kv = settings.key_values();
    RunInfo {
        tool_name: "tmrotor".to_string(),
        tool_version: env!("CARGO_PKG_VERSION").to_string(),
        model_name: model.spec.name.clone(),
        model_text: model.text.clone(),
        settings: kv,
        settings_toml,
        harmonics: basis.harmonics().to_vec(),
        lambda,
        n_mech: system.assembly().n_dof,
        n_therm: crate::system::System::n_therm(system),
        nodes,
        thermal_nodes,
        bearings,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The field names of a struct's `Debug` form (`Name { a: …, b: … }`).
    fn debug_fields(debug: &str) -> Vec<String> {
        let body = debug
            .split_once('{')
            .map_or("", |(_, b)| b.trim_end_matches('}'));
        let mut out = Vec::new();
        let mut depth = 0i32;
        let mut token = String::new();
        for ch in body.chars() {
            match ch {
                '(' | '[' | '{' => depth += 1,
                ')' | ']' | '}' => depth -= 1,
                ':' if depth == 0 && !token.trim().is_empty() => {
                    out.push(token.trim().trim_start_matches(',').trim().to_string());
                    token.clear();
                    continue;
                }
                ',' if depth == 0 => token.clear(),
                _ => {}
            }
            if depth == 0 && ch != ',' {
                token.push(ch);
            }
        }
        out
    }

    #[test]
    fn every_grouped_setting_has_a_flat_key() {
        let s = StudySettings::default();
        let groups = [
            format!("{:?}", s.operating),
            format!("{:?}", s.harmonic),
            format!("{:?}", s.sweep),
            format!("{:?}", s.floquet),
        ];
        let mut fields: Vec<String> = groups.iter().flat_map(|g| debug_fields(g)).collect();
        assert!(fields.len() >= 20, "{fields:?}");
        fields.sort();
        let mut keys: Vec<String> = FLAT_KEYS.iter().map(|k| k.to_string()).collect();
        keys.sort();
        assert_eq!(fields, keys);
        // and the flat form round-trips every value
        let mut custom = StudySettings::default();
        custom.operating.flow_l_min = 7.5;
        custom.harmonic.exact_contacts = true;
        custom.sweep.max_points = 17;
        custom.floquet.verify_orders = vec![4, 6];
        let flat = FlatSettings::from(custom.clone());
        assert_eq!(StudySettings::from(flat), custom);
    }

    #[test]
    fn setting_names_parse_as_in_files_and_unknown_ones_are_listed() {
        assert_eq!(
            parse_name::<StabilityChoice>("sip"),
            Ok(StabilityChoice::Sip)
        );
        assert_eq!(
            parse_name::<StabilityChoice>("exp-sip"),
            Ok(StabilityChoice::ExpSip)
        );
        assert_eq!(
            parse_name::<crate::stability::IntervalMap>("strang"),
            Ok(crate::stability::IntervalMap::Strang)
        );
        let err = parse_name::<StabilityChoice>("exp_sip").expect_err("not a name");
        assert!(err.contains("exp-sip") && err.contains("sip"), "{err}");
    }

    #[test]
    fn primary_basis_keeps_the_harmonics_the_speeds_make() {
        let r = |num, den| Ratio { num, den };
        // λ = 6/5: ω/2 goes, λω/2 = 3ω/5 stays; 7 frequencies, period 10π/ω
        let b = primary_basis(3, r(6, 5)).expect("basis");
        assert_eq!(
            b.harmonics(),
            &[
                r(3, 5),
                r(1, 1),
                r(6, 5),
                r(2, 1),
                r(12, 5),
                r(3, 1),
                r(18, 5)
            ]
        );
        assert_eq!(b.base_den(), 5);
        // λ = 3/2: ω/2 = λω − ω stays, λω/2 = 3ω/4 goes
        let b = primary_basis(2, r(3, 2)).expect("basis");
        assert!(b.harmonics().contains(&r(1, 2)));
        assert!(!b.harmonics().contains(&r(3, 4)));
    }

    /// The grouped settings read and write the flat TOML of earlier versions: every key at
    /// the top level, unknown keys refused.
    #[test]
    fn grouped_settings_keep_the_flat_toml() {
        let text = "flow_l_min = 5.0\ncooling_temp_c = 50.0\norder = 2\nomega_start = 400.0\n\
                    ds_max = 0.1\nthermal = false\nstability_method = \"sip\"\n\
                    sip_intervals = 1024\naft_samples = 64\n";
        let s: StudySettings = toml::from_str(text).expect("flat settings");
        assert_eq!(s.operating.flow_l_min, 5.0);
        assert_eq!(s.operating.cooling_temp_c, 50.0);
        assert!(!s.operating.thermal);
        assert_eq!(s.harmonic.order, 2);
        assert_eq!(s.harmonic.aft_samples, Some(64));
        assert_eq!(s.sweep.omega_start, 400.0);
        assert_eq!(s.sweep.omega_end, 700.0, "absent keys take their defaults");
        assert_eq!(s.sweep.ds_max, 0.1);
        assert_eq!(s.floquet.stability_method, StabilityChoice::Sip);
        assert_eq!(s.floquet.sip_intervals, 1024);
        let back = toml::to_string(&s).expect("write");
        let again: StudySettings = toml::from_str(&back).expect("read back");
        assert_eq!(again, s);
        let mut keys: Vec<String> = s.key_values().into_iter().map(|(k, _)| k).collect();
        keys.sort();
        let mut expected = [
            "flow_l_min",
            "cooling_temp_c",
            "ambient_temp_c",
            "order",
            "omega_start",
            "omega_end",
            "ds_max",
            "max_points",
            "switch_branches",
            "thermal",
            "stability",
            "stability_method",
            "sip_intervals",
            "interval_map",
            "reduction_cutoff_rad_s",
            "aft_samples",
            "half_orders",
            "combination_tones",
            "exact_contacts",
            "verify",
            "verify_orders",
            "verify_max_seconds",
            "model",
        ];
        expected.sort();
        assert_eq!(keys, expected);
        let err = toml::from_str::<StudySettings>("flow_rate = 3.0\n").expect_err("unknown");
        assert!(err.to_string().contains("flow_rate"), "{err}");
    }

    /// Each group refuses its own impossible values, naming the key.
    #[test]
    fn each_group_names_the_refused_key() {
        let mut s = StudySettings::default();
        s.sweep.omega_end = s.sweep.omega_start;
        assert!(
            check_settings(&s)
                .expect_err("refused")
                .to_string()
                .contains("omega_end")
        );
        let mut s = StudySettings::default();
        s.harmonic.order = 13;
        assert!(
            check_settings(&s)
                .expect_err("refused")
                .to_string()
                .contains("order")
        );
        let mut s = StudySettings::default();
        s.floquet.sip_intervals = 511;
        assert!(
            check_settings(&s)
                .expect_err("refused")
                .to_string()
                .contains("even")
        );
        assert!(check_settings(&StudySettings::default()).is_ok());
    }
}
