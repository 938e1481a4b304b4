//! Errors of the model layer.

use thiserror::Error;

/// Why a model file or its assembly was rejected.
#[derive(Debug, Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("{file}: cannot read: {cause}")]
    Io {
        file: String,
        /// (Not a `#[source]`: the message carries it, and a source would print it twice
        /// in an error chain.)
        cause: std::io::Error,
    },
    /// The file is not valid for the format: `path` is the field path
    /// (`bearings[2].inner_node`), `line` the 1-based line when known.
    #[error("{file}{}: {path}: {kind}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Invalid {
        file: String,
        line: Option<usize>,
        path: String,
        kind: InvalidKind,
    },
    /// Several problems of one file, each on its own line (the value checks, and the
    /// structural checks of each shaft, disk, support and bearing, are all reported at
    /// once; at least two).
    #[error("{}", errors.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n"))]
    Several { errors: Vec<ModelError> },
    /// The model is valid but a numerical step of the assembly failed.
    #[error("{file}: {what}")]
    Numerical { file: String, what: String },
}

impl ModelError {
    /// The reason, when the model file was rejected (the first one of several).
    pub fn kind(&self) -> Option<&InvalidKind> {
        match self {
            Self::Invalid { kind, .. } => Some(kind),
            Self::Several { errors } => errors.first().and_then(Self::kind),
            _ => None,
        }
    }

    /// The field path, when the model file was rejected (the first one of several).
    pub fn path(&self) -> Option<&str> {
        match self {
            Self::Invalid { path, .. } => Some(path),
            Self::Several { errors } => errors.first().and_then(Self::path),
            _ => None,
        }
    }

    /// Every problem: the errors of [`ModelError::Several`], or this one.
    pub fn problems(&self) -> Vec<&ModelError> {
        match self {
            Self::Several { errors } => errors.iter().collect(),
            other => vec![other],
        }
    }
}

/// The reason a model file is invalid.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum InvalidKind {
    /// TOML syntax error.
    #[error("syntax error: {0}")]
    Syntax(String),
    /// A key the format does not know.
    #[error("unknown key: {0}")]
    UnknownKey(String),
    /// A required key is absent.
    #[error("missing key: {0}")]
    MissingKey(String),
    /// Wrong type or unit form of a value.
    #[error("wrong type: {0}")]
    WrongType(String),
    /// A node id that no rotor declares.
    #[error("node {0} does not exist (not listed in any rotor)")]
    UnknownNode(u32),
    /// A material id that is not declared.
    #[error("material \"{0}\" does not exist")]
    UnknownMaterial(String),
    /// The same id is declared twice.
    #[error("duplicate id {0}")]
    DuplicateId(String),
    /// A value that must be strictly positive (and finite) is not.
    #[error("must be positive and finite, got {0}")]
    NotPositive(f64),
    /// A value that must be non-negative (and finite) is not.
    #[error("must be non-negative and finite, got {0}")]
    Negative(f64),
    /// A value outside its physical range.
    #[error("{} is out of range: {reason}", short_number(*value))]
    OutOfRange { value: f64, reason: String },
    /// Inner diameter not smaller than outer diameter.
    #[error("inner diameter {inner_m} m must be smaller than outer diameter {outer_m} m")]
    DiameterOrder { inner_m: f64, outer_m: f64 },
    /// A speed ratio that is not a clean rational number.
    #[error("speed ratio {0} is not a clean rational (denominator ≤ 100); write it as \"p/q\"")]
    IrrationalRatio(String),
    /// An element or a coupling that refers to the same node twice, or to nodes of
    /// different rotors where one rotor is required.
    #[error("{0}")]
    BadConnection(String),
    /// Keys that cannot be combined, or a choice with nothing chosen.
    #[error("{0}")]
    Conflict(String),
}

/// A number as a person writes it: plain in the usual range, in exponent form outside
/// (`1e300`, not three hundred digits).
fn short_number(v: f64) -> String {
    if v == 0.0 || (1e-4..1e9).contains(&v.abs()) {
        v.to_string()
    } else {
        format!("{v:e}")
    }
}
