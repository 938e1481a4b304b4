//! Parsing and validation of model files into a [`Model`].

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::error::{InvalidKind, ModelError};
use super::file::{
    BearingSpec, DiskSpec, ForceSpec, ModelFile, NonlinearKind, NonlinearSpec, ShaftSpec,
    SpeedRatioSpec, SupportSpec, SupportTableSpec,
};
use super::reference::{Bound, Key, reference_key as key};
use crate::bearing::ContactLaw;
use crate::hb::Ratio;

/// Largest denominator accepted for a speed ratio given as a number.
pub const MAX_RATIO_DEN: u32 = 100;

/// The built-in dual-rotor model file (paper Tables A.1–A.5, node layout of the spec).
pub const BUILTIN_TOML: &str = include_str!("../../../../models/dual_rotor.toml");

/// Name under which the built-in model reports errors.
pub const BUILTIN_NAME: &str = "<built-in dual_rotor.toml>";
/// The same dual rotor with every value the paper leaves open at its literature default,
/// uncalibrated (`models/dual_rotor_literature.toml`; docs/calibration.md).
pub const LITERATURE_TOML: &str = include_str!("../../../../models/dual_rotor_literature.toml");
/// Name of [`LITERATURE_TOML`] in messages.
pub const LITERATURE_NAME: &str = "<built-in dual_rotor_literature.toml>";

/// Direction of a nodal DoF. See the module docs of [`crate::model`] for the ordering.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dir {
    /// Vertical displacement (gravity acts along −x).
    X = 0,
    /// Horizontal displacement.
    Y = 1,
    /// Slope `dx/dz` of the x–z plane (the paper's θx).
    ThetaX = 2,
    /// Slope `dy/dz` of the y–z plane (the paper's θy).
    ThetaY = 3,
}

/// Number of DoFs per node.
pub const DOF_PER_NODE: usize = 4;

/// A validated model: the file contents plus the derived indexing.
#[derive(Clone, Debug)]
pub struct Model {
    /// File name (or the built-in name) used in error messages.
    pub source: String,
    /// The model file's text as read: what a recording embeds, so that replay rebuilds
    /// exactly this model without the file.
    pub text: String,
    /// The validated file contents.
    pub spec: ModelFile,
    nodes: Vec<u32>,
    node_rotor: Vec<usize>,
    speed_ratios: Vec<SpeedRatio>,
    rayleigh: (f64, f64),
}

impl Model {
    /// The built-in dual rotor of the paper.
    pub fn builtin() -> Result<Self, ModelError> {
        Self::from_str(BUILTIN_TOML, BUILTIN_NAME)
    }

    /// The dual rotor with the literature values of its open parameters (uncalibrated).
    pub fn literature() -> Result<Self, ModelError> {
        Self::from_str(LITERATURE_TOML, LITERATURE_NAME)
    }

    /// Reads and validates a model file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self, ModelError> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text =
            crate::input::read_text(path, crate::input::MAX_INPUT_BYTES).map_err(|cause| {
                ModelError::Io {
                    file: name.clone(),
                    cause,
                }
            })?;
        Self::from_str(&text, &name)
    }

    /// Reads the model file `path` (the built-in model when `None`), applies the values of
    /// `set` ([`super::set`]) and validates the result; the model's `text` is the edited
    /// text. Errors name the file, the path and the reason.
    pub fn load(path: Option<&Path>, set: &super::ModelSet) -> Result<Self, ModelError> {
        let (text, name) = match path {
            Some(path) => {
                let name = path.display().to_string();
                let text = crate::input::read_text(path, crate::input::MAX_INPUT_BYTES).map_err(
                    |cause| ModelError::Io {
                        file: name.clone(),
                        cause,
                    },
                )?;
                (text, name)
            }
            None => (BUILTIN_TOML.to_string(), BUILTIN_NAME.to_string()),
        };
        let text = super::set::apply(&text, &name, set)?;
        // errors of the edited file say so (the value may come from `set`, not the file)
        let name = if set.is_empty() {
            name
        } else {
            format!("{name} (edited by `set`)")
        };
        Self::from_str(&text, &name)
    }

    /// Parses and validates model text; `name` is used in error messages.
    #[allow(clippy::should_implement_trait)]
    pub fn from_str(text: &str, name: &str) -> Result<Self, ModelError> {
        let spec: ModelFile = toml::from_str(text).map_err(|e| {
            let (line, path) = match e.span() {
                Some(span) => {
                    let (l, p) = path_at(text, span.start);
                    (Some(l), p)
                }
                None => (None, String::new()),
            };
            let msg = e.message().to_string();
            let kind = if let Some(rest) = msg.strip_prefix("unknown field ") {
                InvalidKind::UnknownKey(rest.to_string())
            } else if let Some(rest) = msg.strip_prefix("missing field ") {
                InvalidKind::MissingKey(rest.to_string())
            } else if msg.starts_with("invalid type")
                || msg.starts_with("invalid value")
                || msg.starts_with("invalid length")
                || msg.starts_with("unknown variant")
                || msg.starts_with("data did not match")
            {
                InvalidKind::WrongType(msg)
            } else {
                InvalidKind::Syntax(msg)
            };
            ModelError::Invalid {
                file: name.to_string(),
                line,
                path: if path.is_empty() {
                    "(top level)".into()
                } else {
                    path
                },
                kind,
            }
        })?;
        let mut model = Validator::new(name)
            .run(spec)
            .map_err(|e| with_lines(e, text))?;
        model.text = text.to_string();
        Ok(model)
    }

    /// Node ids in DoF order (ascending id).
    pub fn node_ids(&self) -> &[u32] {
        &self.nodes
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of mechanical DoFs (`4 × nodes`).
    pub fn n_dof(&self) -> usize {
        DOF_PER_NODE * self.nodes.len()
    }

    /// Position of node `id` in the DoF ordering.
    pub fn node_index(&self, id: u32) -> Option<usize> {
        self.nodes.binary_search(&id).ok()
    }

    /// Global DoF of node `id` in direction `dir`.
    pub fn dof(&self, id: u32, dir: Dir) -> Option<usize> {
        self.node_index(id).map(|i| dof(i, dir))
    }

    /// Index (into `spec.rotors`) of the rotor owning node index `node_index`.
    pub fn rotor_of(&self, node_index: usize) -> usize {
        self.node_rotor[node_index]
    }

    /// Axial position of every node (m): cumulative element lengths along each rotor, later rotors
    /// shifted so that an inter-shaft bearing's two nodes line up.
    pub fn axial_positions(&self) -> Vec<f64> {
        let model = self;
        let ids = model.node_ids();
        let mut pos: Vec<Option<f64>> = vec![None; ids.len()];
        let idx = |id: u32| model.node_index(id);
        for rotor in &model.spec.rotors {
            let Some(&first) = rotor.nodes.first() else {
                continue;
            };
            // offset from an inter-shaft bearing to an already placed node
            let mut offset = 0.0;
            let mut local: std::collections::BTreeMap<u32, f64> = Default::default();
            local.insert(first, 0.0);
            // walk shafts repeatedly (elements may be listed in any order)
            for _ in 0..rotor.nodes.len() {
                for sh in &model.spec.shafts {
                    if sh.nodes.len() != 2 {
                        continue;
                    }
                    let (a, b) = (sh.nodes[0], sh.nodes[1]);
                    if let (Some(&pa), None) = (local.get(&a), local.get(&b)) {
                        local.insert(b, pa + sh.length_m);
                    } else if let (None, Some(&pb)) = (local.get(&a), local.get(&b)) {
                        local.insert(a, pb - sh.length_m);
                    }
                }
            }
            for b in &model.spec.bearings {
                if let Some(o) = b.outer_node {
                    for (mine, other) in [(o, b.inner_node), (b.inner_node, o)] {
                        if let (Some(&lm), Some(io)) = (local.get(&mine), idx(other))
                            && let Some(po) = pos[io]
                        {
                            offset = po - lm;
                        }
                    }
                }
            }
            for (id, p) in local {
                if let Some(i) = idx(id) {
                    pos[i] = Some(p + offset);
                }
            }
        }
        pos.into_iter().map(|p| p.unwrap_or(0.0)).collect()
    }

    /// Speed ratio of rotor `r` (index into `spec.rotors`).
    pub fn speed_ratio(&self, r: usize) -> SpeedRatio {
        self.speed_ratios[r]
    }

    /// All speed ratios, in rotor order.
    pub fn speed_ratios(&self) -> &[SpeedRatio] {
        &self.speed_ratios
    }

    /// Rayleigh coefficients `(a0 [1/s], a1 [s])`.
    pub fn rayleigh(&self) -> (f64, f64) {
        self.rayleigh
    }

    /// The opaque `[thermal]` table, if present.
    pub fn thermal(&self) -> Option<&toml::Table> {
        self.spec.thermal.as_ref()
    }

    /// Index of material `id` in `spec.materials`.
    pub fn material_index(&self, id: &str) -> Option<usize> {
        self.spec.materials.iter().position(|m| m.id == id)
    }
}

/// Global DoF of node index `node_index` in direction `dir` (node-major `[x, y, θx, θy]`).
#[inline]
pub fn dof(node_index: usize, dir: Dir) -> usize {
    DOF_PER_NODE * node_index + dir as usize
}

/// Parses a speed ratio: `"p/q"`, `"p"`, a decimal string, or a number; numbers must be a
/// rational with denominator ≤ [`MAX_RATIO_DEN`] within 1e-9.
pub fn parse_ratio(spec: &SpeedRatioSpec) -> Result<SpeedRatio, InvalidKind> {
    let bad = |s: String| InvalidKind::IrrationalRatio(s);
    let from_float = |x: f64, text: String| -> Result<SpeedRatio, InvalidKind> {
        if x == 0.0 {
            return Ok(SpeedRatio::ZERO);
        }
        let magnitude = Ratio::approximate(x.abs(), MAX_RATIO_DEN).ok_or(bad(text))?;
        Ok(SpeedRatio {
            negative: x < 0.0,
            magnitude: Some(magnitude),
        })
    };
    match spec {
        SpeedRatioSpec::Number(x) => from_float(*x, x.to_string()),
        SpeedRatioSpec::Text(s) => {
            let t = s.trim();
            if let Some((p, q)) = t.split_once('/') {
                let p = p.trim();
                let (negative, p) = match p.strip_prefix('-') {
                    Some(rest) => (true, rest.trim()),
                    None => (false, p),
                };
                let p: u32 = p.parse().map_err(|_| bad(s.clone()))?;
                let q: u32 = q.trim().parse().map_err(|_| bad(s.clone()))?;
                if q == 0 {
                    return Err(bad(s.clone()));
                }
                if p == 0 {
                    return Ok(SpeedRatio::ZERO);
                }
                Ok(SpeedRatio {
                    negative,
                    magnitude: Some(Ratio::new(p, q).map_err(|_| bad(s.clone()))?),
                })
            } else {
                let x: f64 = t.parse().map_err(|_| bad(s.clone()))?;
                from_float(x, s.clone())
            }
        }
    }
}

/// A rotor's speed over the reference speed ω: a rational number of either sign (negative:
/// the rotor turns against the reference rotor, from +y towards +x; zero: a part that does
/// not spin).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpeedRatio {
    /// Turning against the reference rotor.
    pub negative: bool,
    /// `|ratio|`; `None` for a part that does not spin.
    pub magnitude: Option<Ratio>,
}

impl SpeedRatio {
    /// The reference rotor's own ratio, 1.
    pub const ONE: Self = Self {
        negative: false,
        magnitude: Some(Ratio { num: 1, den: 1 }),
    };
    /// A part that does not spin.
    pub const ZERO: Self = Self {
        negative: false,
        magnitude: None,
    };

    /// The signed value.
    pub fn value(self) -> f64 {
        match self.magnitude {
            None => 0.0,
            Some(r) if self.negative => -r.value(),
            Some(r) => r.value(),
        }
    }
}

impl std::fmt::Display for SpeedRatio {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.magnitude {
            None => f.write_str("0"),
            Some(r) => write!(
                f,
                "{}{}/{}",
                if self.negative { "-" } else { "" },
                r.num,
                r.den
            ),
        }
    }
}

/// Line (1-based) and field path (`disks[1].mass_kg`) of a byte offset in TOML text,
/// found from the table headers above it and the key on its line.
pub(crate) fn path_at(text: &str, offset: usize) -> (usize, String) {
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut current = String::new();
    let mut pos = 0;
    for (i, line) in text.split_inclusive('\n').enumerate() {
        let end = pos + line.len();
        let t = line.trim();
        if let Some(inner) = t.strip_prefix("[[").and_then(|r| r.split("]]").next()) {
            let name = inner.trim().to_string();
            let c = counts.entry(name.clone()).or_insert(0);
            current = format!("{name}[{c}]");
            *c += 1;
        } else if let Some(inner) = t.strip_prefix('[').and_then(|r| r.split(']').next()) {
            current = inner.trim().to_string();
        }
        if offset < end || end == text.len() {
            let is_header = t.starts_with('[');
            let key = if is_header || t.starts_with('#') {
                None
            } else {
                line.split_once('=').map(|(k, _)| k.trim().to_string())
            };
            let path = match key {
                Some(k) if current.is_empty() => k,
                Some(k) => format!("{current}.{k}"),
                None => current,
            };
            return (i + 1, path);
        }
        pos = end;
    }
    (text.lines().count().max(1), current)
}

struct Validator<'a> {
    file: &'a str,
    /// Problems of single values ([`Validator::positive`], [`Validator::non_negative`]):
    /// they do not stop the checks, so a file's value problems are all reported at once.
    found: std::cell::RefCell<Vec<ModelError>>,
    /// An element (shaft, disk, support, bearing) was refused for its structure: the
    /// checks of the whole model (every node has mass, the rotors are held) are skipped,
    /// as they would only report its consequences.
    refused: std::cell::Cell<bool>,
}

type VResult<T> = Result<T, ModelError>;

/// The nodes as the validation has indexed them, and which ones have mass so far.
struct Layout<'a> {
    nodes: &'a [u32],
    node_rotor: &'a [usize],
    has_mass: &'a mut [bool],
}

/// The error with the line of each problem in `text`, found from its path.
fn with_lines(e: ModelError, text: &str) -> ModelError {
    match e {
        ModelError::Invalid {
            file,
            line: None,
            path,
            kind,
        } => ModelError::Invalid {
            file,
            line: super::set::line_of(text, &path),
            path,
            kind,
        },
        ModelError::Several { errors } => ModelError::Several {
            errors: errors.into_iter().map(|e| with_lines(e, text)).collect(),
        },
        other => other,
    }
}

/// One error as itself, more as [`ModelError::Several`].
fn several(mut errors: Vec<ModelError>) -> ModelError {
    if errors.len() == 1 {
        errors.remove(0)
    } else {
        ModelError::Several { errors }
    }
}

impl<'a> Validator<'a> {
    fn new(file: &'a str) -> Self {
        Self {
            file,
            found: std::cell::RefCell::new(Vec::new()),
            refused: std::cell::Cell::new(false),
        }
    }

    /// Runs every check; the value problems found on the way come first, then the problem
    /// that stopped the checks, if any.
    fn run(self, spec: ModelFile) -> VResult<Model> {
        let result = self.check(spec);
        let mut errors = self.found.take();
        // one problem per field (a value refused as negative is not also out of range)
        let mut seen = std::collections::BTreeSet::new();
        errors.retain(|e| seen.insert(e.path().unwrap_or_default().to_string()));
        let errors_then = |e: ModelError, errors: &mut Vec<ModelError>| {
            if !seen.contains(e.path().unwrap_or_default()) {
                errors.push(e);
            }
        };
        match result {
            Ok(model) if errors.is_empty() => Ok(model),
            Ok(_) => Err(several(errors)),
            Err(e) => {
                errors_then(e, &mut errors);
                Err(several(errors))
            }
        }
    }

    fn err(&self, path: impl Into<String>, kind: InvalidKind) -> ModelError {
        ModelError::Invalid {
            file: self.file.to_string(),
            line: None,
            path: path.into(),
            kind,
        }
    }

    /// Records a problem of `path` when `v` is not positive and finite; the checks go on.
    fn positive(&self, path: impl Into<String>, v: f64) -> VResult<()> {
        if !(v.is_finite() && v > 0.0) {
            let e = self.err(path, InvalidKind::NotPositive(v));
            self.found.borrow_mut().push(e);
        }
        Ok(())
    }

    /// Stops the checks with a problem of `path` when `v` is not finite.
    fn finite(&self, path: impl Into<String>, v: f64) -> VResult<()> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(self.err(
                path,
                InvalidKind::OutOfRange {
                    value: v,
                    reason: "must be finite".into(),
                },
            ))
        }
    }

    /// A support's coefficient table: speeds finite, non-negative and strictly
    /// increasing; every coefficient list empty or one finite value per speed; no
    /// constant translational coefficient beside it.
    fn support_table(&self, path: &str, s: &SupportSpec, t: &SupportTableSpec) -> VResult<()> {
        let given = s.constant_keys_given();
        if !given.is_empty() {
            return Err(self.err(
                path,
                InvalidKind::BadConnection(format!(
                    "support {} has both a coefficient table and constant coefficients ({}); \
                     give the translational coefficients one way",
                    s.id,
                    given.join(", ")
                )),
            ));
        }
        let sp = &t.speeds_rad_s;
        if sp.is_empty() {
            return Err(self.err(
                format!("{path}.speeds_rad_s"),
                InvalidKind::BadConnection("needs at least one speed".into()),
            ));
        }
        for (i, &w) in sp.iter().enumerate() {
            self.non_negative(format!("{path}.speeds_rad_s[{i}]"), w)?;
            if i > 0 && w <= sp[i - 1] {
                return Err(self.err(
                    format!("{path}.speeds_rad_s[{i}]"),
                    InvalidKind::OutOfRange {
                        value: w,
                        reason: format!("speeds must increase strictly (after {})", sp[i - 1]),
                    },
                ));
            }
        }
        for (key, col) in t.columns() {
            if !col.is_empty() && col.len() != sp.len() {
                return Err(self.err(
                    format!("{path}.{key}"),
                    InvalidKind::BadConnection(format!(
                        "has {} values for {} speeds",
                        col.len(),
                        sp.len()
                    )),
                ));
            }
            for (i, &v) in col.iter().enumerate() {
                self.finite(format!("{path}.{key}[{i}]"), v)?;
            }
        }
        Ok(())
    }

    /// A `[[nonlinear]]` element: its nodes, the keys its kind needs (and no key of
    /// another kind), their ranges.
    fn nonlinear_element(&self, i: usize, e: &NonlinearSpec, nodes: &[u32]) -> VResult<()> {
        let p = |f: &str| format!("nonlinear[{i}].{f}");
        self.connection(nodes, &p, e.node, e.to_node, "element")?;
        let kind = e.kind;
        let given: [(&str, bool); 5] = [
            ("gap_m", e.gap_m.is_some()),
            ("stiffness_n_m", e.stiffness_n_m.is_some()),
            ("friction_coefficient", e.friction_coefficient.is_some()),
            ("coefficients", e.coefficients.is_some()),
            ("direction_deg", e.direction_deg.is_some()),
        ];
        let (needed, allowed): (&[&str], &[&str]) = match kind {
            NonlinearKind::Rub => (
                &["gap_m", "stiffness_n_m"],
                &["gap_m", "stiffness_n_m", "friction_coefficient"],
            ),
            NonlinearKind::Polynomial => (&["coefficients"], &["coefficients"]),
            NonlinearKind::Unilateral => (
                &["stiffness_n_m", "direction_deg"],
                &["gap_m", "stiffness_n_m", "direction_deg"],
            ),
        };
        for (key, set) in given {
            if set && !allowed.contains(&key) {
                return Err(self.err(
                    p(key),
                    InvalidKind::BadConnection(format!(
                        "a {} element has no {key} (it takes {})",
                        kind.label(),
                        allowed.join(", ")
                    )),
                ));
            }
            if !set && needed.contains(&key) {
                return Err(self.err(
                    p(key),
                    InvalidKind::MissingKey(format!("a {} element needs {key}", kind.label())),
                ));
            }
        }
        if let Some(g) = e.gap_m {
            self.bounded(&p, key!("nonlinear", "gap_m"), g)?;
        }
        if let Some(k) = e.stiffness_n_m {
            self.bounded(&p, key!("nonlinear", "stiffness_n_m"), k)?;
        }
        if let Some(mu) = e.friction_coefficient {
            self.bounded(&p, key!("nonlinear", "friction_coefficient"), mu)?;
        }
        if let Some(a) = e.direction_deg {
            self.bounded(&p, key!("nonlinear", "direction_deg"), a)?;
        }
        if let Some(c) = &e.coefficients {
            if c.is_empty() {
                return Err(self.err(
                    p("coefficients"),
                    InvalidKind::BadConnection("needs at least one coefficient".into()),
                ));
            }
            for (j, &v) in c.iter().enumerate() {
                self.finite(format!("{}[{j}]", p("coefficients")), v)?;
            }
        }
        Ok(())
    }

    /// A `[[forces]]` entry: its node, a finite amplitude, angles, and a frequency the
    /// harmonic basis holds (1 or a rotor's |speed ratio|: the basis of Eq. 34 is built
    /// from those).
    fn harmonic_force(
        &self,
        i: usize,
        f: &ForceSpec,
        nodes: &[u32],
        ratios: &[SpeedRatio],
    ) -> VResult<()> {
        let p = |k: &str| format!("forces[{i}].{k}");
        self.node(nodes, p("node"), f.node)?;
        self.bounded(&p, key!("forces", "amplitude_n"), f.amplitude_n)?;
        self.bounded(&p, key!("forces", "direction_deg"), f.direction_deg)?;
        self.bounded(&p, key!("forces", "phase_deg"), f.phase_deg)?;
        let r = f.frequency_ratio;
        let held = (r - 1.0).abs() < 1e-12
            || ratios
                .iter()
                .any(|s| (s.value().abs() - r).abs() < 1e-12 * r.max(1.0));
        if !(r.is_finite() && r > 0.0 && held) {
            let list: Vec<String> = ratios.iter().map(|s| s.value().abs().to_string()).collect();
            return Err(self.err(
                p("frequency_ratio"),
                InvalidKind::OutOfRange {
                    value: r,
                    reason: format!(
                        "must be 1 or a rotor's |speed ratio| ({}): the harmonic basis is built \
                         from those",
                        list.join(", ")
                    ),
                },
            ));
        }
        Ok(())
    }

    /// Checks `v`, the value of `key` in the entry whose keys `p` names, against the
    /// bound the reference gives the key: a value not positive or negative where it must
    /// not be is recorded and the checks go on ([`Validator::positive`],
    /// [`Validator::non_negative`]); a value not finite where it must be, or out of an
    /// interval, stops them.
    fn bounded(&self, p: &dyn Fn(&str) -> String, key: &Key, v: f64) -> VResult<()> {
        let path = p(key.key);
        match key.bound {
            Bound::Free => Ok(()),
            Bound::Positive => self.positive(path, v),
            Bound::NonNegative => self.non_negative(path, v),
            Bound::Finite => self.finite(path, v),
            bound @ Bound::Within { .. } if bound.admits(v) => Ok(()),
            bound @ Bound::Within { .. } => Err(self.err(
                path,
                InvalidKind::OutOfRange {
                    value: v,
                    reason: format!("must lie {}", bound.text()),
                },
            )),
        }
    }

    fn non_negative(&self, path: impl Into<String>, v: f64) -> VResult<()> {
        if !(v.is_finite() && v >= 0.0) {
            let e = self.err(path, InvalidKind::Negative(v));
            self.found.borrow_mut().push(e);
        }
        Ok(())
    }

    fn unique<'s>(&self, section: &str, ids: impl Iterator<Item = &'s str>) -> VResult<()> {
        let mut seen = BTreeSet::new();
        for (i, id) in ids.enumerate() {
            if !seen.insert(id) {
                self.keep(Err(self.err(
                    format!("{section}[{i}].id"),
                    InvalidKind::DuplicateId(format!("\"{id}\"")),
                )));
            }
        }
        Ok(())
    }

    /// Records the structural problem of one element, if any; the checks go on with the
    /// next element.
    fn keep(&self, r: VResult<()>) {
        if let Err(e) = r {
            self.refused.set(true);
            self.found.borrow_mut().push(e);
        }
    }

    fn node(&self, nodes: &[u32], path: impl Into<String>, id: u32) -> VResult<usize> {
        nodes
            .binary_search(&id)
            .map_err(|_| self.err(path, InvalidKind::UnknownNode(id)))
    }

    fn material(&self, spec: &ModelFile, path: impl Into<String>, id: &str) -> VResult<()> {
        if !spec.materials.iter().any(|m| m.id == id) {
            self.keep(Err(
                self.err(path, InvalidKind::UnknownMaterial(id.to_string()))
            ));
        }
        Ok(())
    }

    /// The shaft elements of each rotor lie along its axis one after another: an element
    /// runs from its first node to its second in +z, so the elements place every node, and
    /// two elements of a rotor must not cover the same stretch of the axis (as an element
    /// given backwards, `[3, 2]` between `[1, 2]` and `[3, 4]`, would).
    fn shafts_in_line(&self, spec: &ModelFile, nodes: &[u32], node_rotor: &[usize]) -> VResult<()> {
        let index = |id: u32| nodes.binary_search(&id).ok();
        let mut z: Vec<Option<f64>> = vec![None; nodes.len()];
        // place each rotor's nodes from its elements (elements may be listed in any order)
        for _ in 0..spec.shafts.len() {
            let mut placed_any = false;
            for s in &spec.shafts {
                let (Some(a), Some(b)) = (index(s.nodes[0]), index(s.nodes[1])) else {
                    continue;
                };
                match (z[a], z[b]) {
                    (Some(za), None) => z[b] = Some(za + s.length_m),
                    (None, Some(zb)) => z[a] = Some(zb - s.length_m),
                    (None, None)
                        if !z
                            .iter()
                            .enumerate()
                            .any(|(k, v)| v.is_some() && node_rotor[k] == node_rotor[a]) =>
                    {
                        z[a] = Some(0.0);
                        z[b] = Some(s.length_m);
                    }
                    _ => continue,
                }
                placed_any = true;
            }
            if !placed_any {
                break;
            }
        }
        let span = |s: &ShaftSpec| -> Option<(f64, f64)> {
            let (a, b) = (z[index(s.nodes[0])?]?, z[index(s.nodes[1])?]?);
            Some((a.min(b), a.max(b)))
        };
        for (j, sj) in spec.shafts.iter().enumerate() {
            let Some((lo_j, hi_j)) = span(sj) else {
                continue;
            };
            for (i, si) in spec.shafts[..j].iter().enumerate() {
                let Some((lo_i, hi_i)) = span(si) else {
                    continue;
                };
                let same_rotor = index(si.nodes[0]).map(|k| node_rotor[k])
                    == index(sj.nodes[0]).map(|k| node_rotor[k]);
                let overlap = hi_i.min(hi_j) - lo_i.max(lo_j);
                if same_rotor && overlap > 1e-9 * (hi_j - lo_j).max(hi_i - lo_i) {
                    return Err(self.err(
                        format!("shafts[{j}].nodes"),
                        InvalidKind::BadConnection(format!(
                            "element {}–{} covers z = {lo_j:.6}…{hi_j:.6} m of its rotor's \
                             axis, which shafts[{i}] (element {}–{}) already covers \
                             ({lo_i:.6}…{hi_i:.6} m): an element runs from its first node \
                             to its second along the axis, so list its nodes in that order",
                            sj.nodes[0], sj.nodes[1], si.nodes[0], si.nodes[1]
                        )),
                    ));
                }
            }
        }
        Ok(())
    }

    fn check(&self, spec: ModelFile) -> VResult<Model> {
        // Gravity.
        let top = |k: &str| format!("gravity.{k}");
        self.bounded(
            &top,
            key!("gravity", "acceleration_m_s2"),
            spec.gravity.acceleration_m_s2,
        )?;

        let rayleigh = self.damping(spec.damping.as_ref())?;
        self.materials(&spec)?;
        let (nodes, node_rotor, speed_ratios) = self.rotors(&spec)?;
        let mut has_mass = vec![false; nodes.len()];

        // Shaft elements.
        let mut pairs = BTreeSet::new();
        let mut layout = Layout {
            nodes: &nodes,
            node_rotor: &node_rotor,
            has_mass: &mut has_mass,
        };
        for (i, s) in spec.shafts.iter().enumerate() {
            self.keep(self.shaft_element(&spec, i, s, &mut layout, &mut pairs));
        }
        if !self.refused.get() {
            self.keep(self.shafts_in_line(&spec, &nodes, &node_rotor));
        }

        // Disks.
        self.unique("disks", spec.disks.iter().map(|d| d.id.as_str()))?;
        for (i, d) in spec.disks.iter().enumerate() {
            self.keep(self.disk(i, d, &mut layout));
        }
        if let Some(n) = has_mass.iter().position(|&m| !m)
            && !self.refused.get()
        {
            return Err(self.err(
                format!("rotors[{}].nodes", node_rotor[n]),
                InvalidKind::BadConnection(format!(
                    "node {} has no shaft element and no disk with diametral inertia, so it has no mass",
                    nodes[n]
                )),
            ));
        }

        // Supports.
        self.unique("supports", spec.supports.iter().map(|s| s.id.as_str()))?;
        for (i, s) in spec.supports.iter().enumerate() {
            self.keep(self.support(i, s, &nodes));
        }

        self.bearings(&spec, &nodes)?;
        self.unique("nonlinear", spec.nonlinear.iter().map(|e| e.id.as_str()))?;
        for (i, e) in spec.nonlinear.iter().enumerate() {
            self.keep(self.nonlinear_element(i, e, &nodes));
        }
        self.unique("forces", spec.forces.iter().map(|f| f.id.as_str()))?;
        for (i, f) in spec.forces.iter().enumerate() {
            self.keep(self.harmonic_force(i, f, &nodes, &speed_ratios));
        }
        if !self.refused.get() {
            self.held_to_ground(&spec, &nodes)?;
        }

        Ok(Model {
            source: self.file.to_string(),
            text: String::new(),
            spec,
            nodes,
            node_rotor,
            speed_ratios,
            rayleigh,
        })
    }
    /// A `[[shafts]]` entry: two different nodes of one rotor, not joined twice
    /// (`pairs`), positive lengths and diameters in order, a known material.
    fn shaft_element(
        &self,
        spec: &ModelFile,
        i: usize,
        s: &ShaftSpec,
        layout: &mut Layout<'_>,
        pairs: &mut BTreeSet<(usize, usize)>,
    ) -> VResult<()> {
        let p = |f: &str| format!("shafts[{i}].{f}");
        if s.nodes.len() != 2 {
            return Err(self.err(
                p("nodes"),
                InvalidKind::WrongType(format!(
                    "expected exactly 2 node ids, got {}",
                    s.nodes.len()
                )),
            ));
        }
        let a = self.node(layout.nodes, format!("shafts[{i}].nodes[0]"), s.nodes[0])?;
        let b = self.node(layout.nodes, format!("shafts[{i}].nodes[1]"), s.nodes[1])?;
        if a == b {
            return Err(self.err(
                p("nodes"),
                InvalidKind::BadConnection(format!(
                    "an element needs two different nodes, got {} twice",
                    s.nodes[0]
                )),
            ));
        }
        if layout.node_rotor[a] != layout.node_rotor[b] {
            return Err(self.err(
                    p("nodes"),
                    InvalidKind::BadConnection(format!(
                        "nodes {} and {} belong to different rotors; couple rotors with a bearing or support",
                        s.nodes[0], s.nodes[1]
                    )),
                ));
        }
        if !pairs.insert((a.min(b), a.max(b))) {
            return Err(self.err(
                p("nodes"),
                InvalidKind::DuplicateId(format!("element {}–{}", s.nodes[0], s.nodes[1])),
            ));
        }
        self.bounded(&p, key!("shafts", "length_m"), s.length_m)?;
        self.bounded(&p, key!("shafts", "outer_diameter_m"), s.outer_diameter_m)?;
        self.bounded(&p, key!("shafts", "inner_diameter_m"), s.inner_diameter_m)?;
        if s.inner_diameter_m >= s.outer_diameter_m {
            return Err(self.err(
                p("inner_diameter_m"),
                InvalidKind::DiameterOrder {
                    inner_m: s.inner_diameter_m,
                    outer_m: s.outer_diameter_m,
                },
            ));
        }
        if let Some(v) = s.outer_diameter_end_m {
            self.bounded(&p, key!("shafts", "outer_diameter_end_m"), v)?;
        }
        if let Some(v) = s.inner_diameter_end_m {
            self.bounded(&p, key!("shafts", "inner_diameter_end_m"), v)?;
        }
        let (end_out, end_in) = s.end_diameters();
        if end_in >= end_out {
            return Err(self.err(
                p("inner_diameter_end_m"),
                InvalidKind::DiameterOrder {
                    inner_m: end_in,
                    outer_m: end_out,
                },
            ));
        }
        self.material(spec, p("material"), &s.material)?;
        layout.has_mass[a] = true;
        layout.has_mass[b] = true;
        Ok(())
    }

    /// A `[[disks]]` entry: its node, positive mass, non-negative inertias and
    /// eccentricity, a finite phase.
    fn disk(&self, i: usize, d: &DiskSpec, layout: &mut Layout<'_>) -> VResult<()> {
        let p = |f: &str| format!("disks[{i}].{f}");
        let n = self.node(layout.nodes, p("node"), d.node)?;
        self.bounded(&p, key!("disks", "mass_kg"), d.mass_kg)?;
        self.bounded(
            &p,
            key!("disks", "polar_inertia_kg_m2"),
            d.polar_inertia_kg_m2,
        )?;
        self.bounded(
            &p,
            key!("disks", "diametral_inertia_kg_m2"),
            d.diametral_inertia_kg_m2,
        )?;
        self.bounded(&p, key!("disks", "eccentricity_m"), d.eccentricity_m)?;
        self.bounded(&p, key!("disks", "phase_deg"), d.phase_deg)?;
        if d.diametral_inertia_kg_m2 > 0.0 {
            layout.has_mass[n] = true;
        }
        Ok(())
    }

    /// The nodes of a two-node entry (`what`: `support`, `element`): `node`, and `to_node`
    /// when given, known and different; `p` names a key of the entry.
    fn connection(
        &self,
        nodes: &[u32],
        p: &dyn Fn(&str) -> String,
        node: u32,
        to_node: Option<u32>,
        what: &str,
    ) -> VResult<()> {
        self.node(nodes, p("node"), node)?;
        if let Some(t) = to_node {
            self.node(nodes, p("to_node"), t)?;
            if t == node {
                return Err(self.err(
                    p("to_node"),
                    InvalidKind::BadConnection(format!("{what} connects node {t} to itself")),
                ));
            }
        }
        Ok(())
    }

    /// A `[[supports]]` entry: its nodes, non-negative direct and finite cross-coupled
    /// coefficients, its coefficient table.
    fn support(&self, i: usize, s: &SupportSpec, nodes: &[u32]) -> VResult<()> {
        let p = |f: &str| format!("supports[{i}].{f}");
        self.connection(nodes, &p, s.node, s.to_node, "support")?;
        self.bounded(&p, key!("supports", "stiffness_n_m"), s.stiffness_n_m)?;
        self.bounded(&p, key!("supports", "damping_n_s_m"), s.damping_n_s_m)?;
        for (f, v) in [
            (key!("supports", "stiffness_xx_n_m"), s.stiffness_xx_n_m),
            (key!("supports", "stiffness_yy_n_m"), s.stiffness_yy_n_m),
            (key!("supports", "damping_xx_n_s_m"), s.damping_xx_n_s_m),
            (key!("supports", "damping_yy_n_s_m"), s.damping_yy_n_s_m),
        ] {
            if let Some(v) = v {
                self.bounded(&p, f, v)?;
            }
        }
        for (f, v) in [
            (key!("supports", "stiffness_xy_n_m"), s.stiffness_xy_n_m),
            (key!("supports", "stiffness_yx_n_m"), s.stiffness_yx_n_m),
            (key!("supports", "damping_xy_n_s_m"), s.damping_xy_n_s_m),
            (key!("supports", "damping_yx_n_s_m"), s.damping_yx_n_s_m),
        ] {
            self.bounded(&p, f, v)?;
        }
        self.bounded(
            &p,
            key!("supports", "rotational_stiffness_n_m_rad"),
            s.rotational_stiffness_n_m_rad,
        )?;
        if let Some(t) = &s.table {
            self.support_table(&p("table"), s, t)?;
        }
        Ok(())
    }

    /// Rayleigh coefficients `(a0, a1)` from `[damping]`: given directly, or from a damping
    /// ratio at two frequencies; none without the table.
    fn damping(&self, damping: Option<&super::file::DampingSpec>) -> VResult<(f64, f64)> {
        Ok(match damping {
            None => (0.0, 0.0),
            Some(d) => {
                let direct = d.a0_1_s.is_some() || d.a1_s.is_some();
                let modal = d.damping_ratio.is_some() || d.frequencies_rad_s.is_some();
                match (direct, modal) {
                    (true, true) => {
                        return Err(self.err(
                        "damping",
                        InvalidKind::Conflict(
                            "give either a0_1_s/a1_s or damping_ratio/frequencies_rad_s, not both"
                                .into(),
                        ),
                    ));
                    }
                    (false, false) => {
                        return Err(self.err(
                            "damping",
                            InvalidKind::Conflict(
                                "give a0_1_s/a1_s or damping_ratio with frequencies_rad_s".into(),
                            ),
                        ));
                    }
                    (true, false) => {
                        let a0 = d.a0_1_s.unwrap_or(0.0);
                        let a1 = d.a1_s.unwrap_or(0.0);
                        let p = |k: &str| format!("damping.{k}");
                        self.bounded(&p, key!("damping", "a0_1_s"), a0)?;
                        self.bounded(&p, key!("damping", "a1_s"), a1)?;
                        (a0, a1)
                    }
                    (false, true) => {
                        let zeta = d.damping_ratio.ok_or_else(|| {
                            self.err("damping", InvalidKind::MissingKey("`damping_ratio`".into()))
                        })?;
                        let [w1, w2] = d.frequencies_rad_s.ok_or_else(|| {
                            self.err(
                                "damping",
                                InvalidKind::MissingKey("`frequencies_rad_s`".into()),
                            )
                        })?;
                        let p = |k: &str| format!("damping.{k}");
                        self.bounded(&p, key!("damping", "damping_ratio"), zeta)?;
                        self.positive("damping.frequencies_rad_s[0]", w1)?;
                        self.positive("damping.frequencies_rad_s[1]", w2)?;
                        if (w1 - w2).abs() <= 1e-12 * w1.max(w2) {
                            return Err(self.err(
                                "damping.frequencies_rad_s",
                                InvalidKind::OutOfRange {
                                    value: w2,
                                    reason: "the two frequencies must differ".into(),
                                },
                            ));
                        }
                        rayleigh_from_ratio(zeta, w1, w2)
                    }
                }
            }
        })
    }

    /// The materials: unique ids, each value within its range.
    fn materials(&self, spec: &ModelFile) -> VResult<()> {
        self.unique("materials", spec.materials.iter().map(|m| m.id.as_str()))?;
        for (i, m) in spec.materials.iter().enumerate() {
            let p = |f: &str| format!("materials[{i}].{f}");
            self.bounded(
                &p,
                key!("materials", "youngs_modulus_pa"),
                m.youngs_modulus_pa,
            )?;
            self.bounded(&p, key!("materials", "density_kg_m3"), m.density_kg_m3)?;
            self.bounded(&p, key!("materials", "poisson_ratio"), m.poisson_ratio)?;
            for (f, v) in [
                (
                    key!("materials", "specific_heat_j_kg_k"),
                    m.specific_heat_j_kg_k,
                ),
                (
                    key!("materials", "conductivity_w_m_k"),
                    m.conductivity_w_m_k,
                ),
                (key!("materials", "expansion_1_k"), m.expansion_1_k),
            ] {
                if let Some(v) = v {
                    self.bounded(&p, f, v)?;
                }
            }
        }
        Ok(())
    }

    /// The rotors: unique ids, speed ratios, and each node in exactly one rotor. Returns the
    /// node ids in ascending order, the rotor of each, and the speed ratios.
    fn rotors(&self, spec: &ModelFile) -> VResult<(Vec<u32>, Vec<usize>, Vec<SpeedRatio>)> {
        if spec.rotors.is_empty() {
            return Err(self.err("rotors", InvalidKind::MissingKey("`rotors`".into())));
        }
        self.unique("rotors", spec.rotors.iter().map(|r| r.id.as_str()))?;
        let mut owner: BTreeMap<u32, usize> = BTreeMap::new();
        let mut speed_ratios = Vec::with_capacity(spec.rotors.len());
        for (r, rotor) in spec.rotors.iter().enumerate() {
            speed_ratios.push(
                parse_ratio(&rotor.speed_ratio)
                    .map_err(|k| self.err(format!("rotors[{r}].speed_ratio"), k))?,
            );
            if rotor.nodes.is_empty() {
                return Err(self.err(
                    format!("rotors[{r}].nodes"),
                    InvalidKind::Conflict("a rotor needs at least one node".into()),
                ));
            }
            for (j, &n) in rotor.nodes.iter().enumerate() {
                if owner.insert(n, r).is_some() {
                    return Err(self.err(
                        format!("rotors[{r}].nodes[{j}]"),
                        InvalidKind::DuplicateId(format!("node {n}")),
                    ));
                }
            }
        }
        let nodes: Vec<u32> = owner.keys().copied().collect();
        let node_rotor: Vec<usize> = owner.values().copied().collect();
        Ok((nodes, node_rotor, speed_ratios))
    }

    /// The bearings: unique ids, nodes, materials, geometry and the source of their
    /// linearised stiffness.
    fn bearings(&self, spec: &ModelFile, nodes: &[u32]) -> VResult<()> {
        self.unique("bearings", spec.bearings.iter().map(|b| b.id.as_str()))?;
        for (i, b) in spec.bearings.iter().enumerate() {
            self.keep(self.bearing(spec, nodes, i, b));
        }
        Ok(())
    }

    /// One bearing: its nodes, materials, geometry and contact data.
    fn bearing(&self, spec: &ModelFile, nodes: &[u32], i: usize, b: &BearingSpec) -> VResult<()> {
        let p = |f: &str| format!("bearings[{i}].{f}");
        self.node(nodes, p("inner_node"), b.inner_node)?;
        if let Some(o) = b.outer_node {
            self.node(nodes, p("outer_node"), o)?;
            if o == b.inner_node {
                return Err(self.err(
                    p("outer_node"),
                    InvalidKind::BadConnection(format!(
                        "inner and outer ring on the same node {o}"
                    )),
                ));
            }
        }
        self.material(spec, p("material"), &b.material)?;
        if let Some(h) = &b.housing_material {
            self.material(spec, p("housing_material"), h)?;
        }
        for (f, v) in [
            (
                key!("bearings", "inner_race_diameter_m"),
                b.inner_race_diameter_m,
            ),
            (
                key!("bearings", "outer_race_diameter_m"),
                b.outer_race_diameter_m,
            ),
            (key!("bearings", "hertz_stiffness"), b.hertz_stiffness),
        ] {
            self.bounded(&p, f, v)?;
        }
        // the geometry record: checked where given
        for (f, v) in [
            (key!("bearings", "bore_diameter_m"), b.bore_diameter_m),
            (key!("bearings", "pitch_diameter_m"), b.pitch_diameter_m),
            (key!("bearings", "outside_diameter_m"), b.outside_diameter_m),
            (key!("bearings", "element_diameter_m"), b.element_diameter_m),
            (key!("bearings", "width_m"), b.width_m),
        ] {
            if let Some(v) = v {
                self.bounded(&p, f, v)?;
            }
        }
        if let Some(r) = b.shaft_inner_radius_m {
            self.bounded(&p, key!("bearings", "shaft_inner_radius_m"), r)?;
        }
        // Radial order of the diameters given: bore < inner race < pitch < outer race
        // < outside.
        let order: Vec<(&str, f64)> = [
            ("bore_diameter_m", b.bore_diameter_m),
            ("inner_race_diameter_m", Some(b.inner_race_diameter_m)),
            ("pitch_diameter_m", b.pitch_diameter_m),
            ("outer_race_diameter_m", Some(b.outer_race_diameter_m)),
            ("outside_diameter_m", b.outside_diameter_m),
        ]
        .into_iter()
        .filter_map(|(f, v)| v.map(|v| (f, v)))
        .collect();
        for w in order.windows(2) {
            if w[0].1 >= w[1].1 {
                return Err(self.err(
                    p(w[0].0),
                    InvalidKind::DiameterOrder {
                        inner_m: w[0].1,
                        outer_m: w[1].1,
                    },
                ));
            }
        }
        if !(3..=1000).contains(&b.element_count) {
            return Err(self.err(
                p("element_count"),
                InvalidKind::OutOfRange {
                    value: f64::from(b.element_count),
                    reason: "a radial bearing has 3 to 1000 rolling elements".into(),
                },
            ));
        }
        self.bounded(
            &p,
            key!("bearings", "initial_clearance_m"),
            b.initial_clearance_m,
        )?;
        match (b.kind, b.roller_length_m) {
            (ContactLaw::Roller, None) => {
                return Err(self.err(
                    p("roller_length_m"),
                    InvalidKind::MissingKey("`roller_length_m` (required for rollers)".into()),
                ));
            }
            (ContactLaw::Ball, Some(_)) => {
                return Err(self.err(
                    p("roller_length_m"),
                    InvalidKind::Conflict("a ball bearing has no roller length".into()),
                ));
            }
            (_, Some(v)) => self.bounded(&p, key!("bearings", "roller_length_m"), v)?,
            _ => {}
        }
        for (f, v) in [
            (key!("bearings", "housing_radius_m"), b.housing_radius_m),
            (key!("bearings", "housing_length_m"), b.housing_length_m),
            (
                key!("bearings", "housing_part_length_m"),
                b.housing_part_length_m,
            ),
            (
                key!("bearings", "outer_shaft_radius_m"),
                b.outer_shaft_radius_m,
            ),
            (
                key!("bearings", "linear_stiffness_n_m"),
                b.linear_stiffness_n_m,
            ),
            (
                key!("bearings", "linearization_load_n"),
                b.linearization_load_n,
            ),
        ] {
            if let Some(v) = v {
                self.bounded(&p, f, v)?;
            }
        }
        if b.linear_stiffness_n_m.is_some() && b.linearization_load_n.is_some() {
            return Err(self.err(
                p("linearization_load_n"),
                InvalidKind::Conflict(
                    "give linear_stiffness_n_m or linearization_load_n, not both".into(),
                ),
            ));
        }
        if !spec.gravity.enabled
            && b.linear_stiffness_n_m.is_none()
            && b.linearization_load_n.is_none()
        {
            return Err(self.err(
            format!("bearings[{i}]"),
            InvalidKind::Conflict(
                "with gravity off the linearised stiffness cannot come from the static gravity load: give linear_stiffness_n_m or linearization_load_n".into(),
            ),
        ));
        }
        Ok(())
    }
}

impl Validator<'_> {
    /// With gravity on, every node must be connected to the ground through shaft elements,
    /// supports and bearings: a part that is not would fall freely as a rigid body (zero
    /// stiffness), and no static equilibrium could be found for it. (A free-free rotor
    /// without gravity is valid: its modes are a classic check.)
    fn held_to_ground(&self, spec: &ModelFile, nodes: &[u32]) -> VResult<()> {
        if !spec.gravity.enabled {
            return Ok(());
        }
        let n = nodes.len();
        let ground = n;
        let mut parent: Vec<usize> = (0..=n).collect();
        fn find(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let index = |id: u32| nodes.binary_search(&id).ok();
        let mut join = |a: Option<usize>, b: Option<usize>| {
            if let (Some(a), Some(b)) = (a, b) {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra] = rb;
            }
        };
        for sh in &spec.shafts {
            for w in sh.nodes.windows(2) {
                join(index(w[0]), index(w[1]));
            }
        }
        for su in &spec.supports {
            join(index(su.node), su.to_node.map_or(Some(ground), index));
        }
        for b in &spec.bearings {
            join(
                index(b.inner_node),
                b.outer_node.map_or(Some(ground), index),
            );
        }
        // a polynomial support with a linear term holds; a rub or a stop acts only
        // beyond its gap
        for e in &spec.nonlinear {
            let linear = e
                .coefficients
                .as_ref()
                .and_then(|c| c.first())
                .is_some_and(|&c1| c1 > 0.0);
            if e.kind == NonlinearKind::Polynomial && linear {
                join(index(e.node), e.to_node.map_or(Some(ground), index));
            }
        }
        let g = find(&mut parent, ground);
        for (i, &id) in nodes.iter().enumerate() {
            if find(&mut parent, i) != g {
                let rotor = spec
                    .rotors
                    .iter()
                    .position(|r| r.nodes.contains(&id))
                    .unwrap_or(0);
                return Err(self.err(
                    format!("rotors[{rotor}]"),
                    InvalidKind::BadConnection(format!(
                        "node {id} is not held: no chain of shaft elements, supports and \
                         bearings leads from it to the ground, so under gravity it would fall \
                         freely as a rigid body with no static equilibrium (add a support or \
                         a bearing to ground, or, for a free-free rotor, set [gravity] \
                         enabled = false)"
                    )),
                ));
            }
        }
        Ok(())
    }
}

/// Rayleigh coefficients giving modal damping ratio `zeta` at `w1` and `w2` (rad/s):
/// from `ζ(ω) = a0/(2ω) + a1 ω/2` at both frequencies,
/// `a0 = 2ζ ω1 ω2/(ω1+ω2)`, `a1 = 2ζ/(ω1+ω2)`.
pub fn rayleigh_from_ratio(zeta: f64, w1: f64, w2: f64) -> (f64, f64) {
    (2.0 * zeta * w1 * w2 / (w1 + w2), 2.0 * zeta / (w1 + w2))
}
