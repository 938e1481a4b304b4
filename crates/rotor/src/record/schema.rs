//! The schemas and topics of a recording.
//!
//! Every message is protobuf-encoded following the MCAP well-known profile for protobuf:
//! schema encoding `protobuf`, schema name = fully qualified message name, schema data = a
//! binary `FileDescriptorSet` holding the file that defines the message and all its
//! imports. These descriptor sets are compiled from `proto/` into `schemas/` (one file per
//! message, named after it) by `tools/regen-schemas.sh`; `tests/record_schemas.rs`
//! recompiles them and fails when `schemas/` is stale. They are embedded here so that the
//! binary needs neither `proto/` nor a protobuf compiler at run time.

/// A message type published in recordings, with its compiled descriptor set.
#[derive(Clone, Copy, Debug)]
pub struct SchemaEntry {
    /// Fully qualified message name (the MCAP schema name).
    pub name: &'static str,
    /// The `.proto` file that defines it, relative to `proto/`.
    pub proto_file: &'static str,
    /// Binary `FileDescriptorSet` of that file with all imports, from `schemas/`.
    pub descriptor_set: &'static [u8],
}

macro_rules! schema {
    ($name:literal, $file:literal) => {
        SchemaEntry {
            name: $name,
            proto_file: $file,
            descriptor_set: include_bytes!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../schemas/",
                $name,
                ".binpb"
            )),
        }
    };
}

pub const RUN_INFO: SchemaEntry = schema!("tmrotor.v1.RunInfo", "tmrotor/v1/run_info.proto");
pub const POINT_SUMMARY: SchemaEntry =
    schema!("tmrotor.v1.PointSummary", "tmrotor/v1/point_summary.proto");
pub const HARMONICS: SchemaEntry = schema!("tmrotor.v1.Harmonics", "tmrotor/v1/harmonics.proto");
pub const ORBITS: SchemaEntry = schema!("tmrotor.v1.Orbits", "tmrotor/v1/orbits.proto");
pub const TEMPERATURES: SchemaEntry =
    schema!("tmrotor.v1.Temperatures", "tmrotor/v1/temperatures.proto");
pub const CLEARANCES: SchemaEntry = schema!("tmrotor.v1.Clearances", "tmrotor/v1/clearances.proto");
pub const BEARING_LOADS: SchemaEntry =
    schema!("tmrotor.v1.BearingLoads", "tmrotor/v1/bearing_loads.proto");
pub const THERMAL_FORCES: SchemaEntry = schema!(
    "tmrotor.v1.ThermalForces",
    "tmrotor/v1/thermal_forces.proto"
);
pub const FLOQUET: SchemaEntry = schema!("tmrotor.v1.Floquet", "tmrotor/v1/floquet.proto");
pub const BIFURCATION: SchemaEntry =
    schema!("tmrotor.v1.Bifurcation", "tmrotor/v1/bifurcation.proto");
pub const TRUNCATION_CHECK: SchemaEntry = schema!(
    "tmrotor.v1.TruncationCheck",
    "tmrotor/v1/truncation_check.proto"
);
pub const BRANCH_INFO: SchemaEntry =
    schema!("tmrotor.v1.BranchInfo", "tmrotor/v1/branch_info.proto");
pub const MAP_INFO: SchemaEntry = schema!("tmrotor.v1.MapInfo", "tmrotor/v1/operating_map.proto");
pub const MAP_CURVE: SchemaEntry = schema!("tmrotor.v1.MapCurve", "tmrotor/v1/operating_map.proto");
pub const MAP_PAIR_END: SchemaEntry =
    schema!("tmrotor.v1.MapPairEnd", "tmrotor/v1/operating_map.proto");
pub const MAP_REGION: SchemaEntry =
    schema!("tmrotor.v1.MapRegion", "tmrotor/v1/operating_map.proto");
pub const TRANSIENT_INFO: SchemaEntry =
    schema!("tmrotor.v1.TransientInfo", "tmrotor/v1/transient.proto");
pub const REVOLUTION: SchemaEntry = schema!("tmrotor.v1.Revolution", "tmrotor/v1/transient.proto");
pub const SAMPLES: SchemaEntry = schema!("tmrotor.v1.Samples", "tmrotor/v1/transient.proto");
pub const SCENE_UPDATE: SchemaEntry = schema!("foxglove.SceneUpdate", "foxglove/SceneUpdate.proto");
pub const LOG: SchemaEntry = schema!("foxglove.Log", "foxglove/Log.proto");
pub const FRAME_TRANSFORM: SchemaEntry =
    schema!("foxglove.FrameTransform", "foxglove/FrameTransform.proto");

/// Every schema a recording or an operating map may contain.
pub const ALL_SCHEMAS: [SchemaEntry; 22] = [
    RUN_INFO,
    POINT_SUMMARY,
    HARMONICS,
    ORBITS,
    TEMPERATURES,
    CLEARANCES,
    BEARING_LOADS,
    THERMAL_FORCES,
    FLOQUET,
    BIFURCATION,
    BRANCH_INFO,
    SCENE_UPDATE,
    LOG,
    FRAME_TRANSFORM,
    MAP_INFO,
    MAP_CURVE,
    MAP_PAIR_END,
    MAP_REGION,
    TRANSIENT_INFO,
    REVOLUTION,
    SAMPLES,
    TRUNCATION_CHECK,
];

/// A topic of a recording: name, message type, meaning (see `schemas/README.md`).
#[derive(Clone, Copy, Debug)]
pub struct Topic {
    pub name: &'static str,
    pub schema: SchemaEntry,
    pub meaning: &'static str,
}

pub const TOPIC_RUN_INFO: Topic = Topic {
    name: "/run_info",
    schema: RUN_INFO,
    meaning: "run description: basis, λ, nodes, bearings, settings, tool version (once)",
};
pub const TOPIC_SUMMARY: Topic = Topic {
    name: "/summary",
    schema: POINT_SUMMARY,
    meaning: "per point: ω, arc length, RMS amplitude per node (Eq. 35), stability, residuals",
};
pub const TOPIC_HARMONICS: Topic = Topic {
    name: "/harmonics",
    schema: HARMONICS,
    meaning: "harmonic coefficients of all mechanical and thermal DoFs",
};
pub const TOPIC_ORBITS: Topic = Topic {
    name: "/orbits",
    schema: ORBITS,
    meaning: "x, y of every dynamic node over one period",
};
pub const TOPIC_TEMPERATURES: Topic = Topic {
    name: "/temperatures",
    schema: TEMPERATURES,
    meaning: "mean, min, max temperature per thermal node",
};
pub const TOPIC_CLEARANCE: Topic = Topic {
    name: "/clearance",
    schema: CLEARANCES,
    meaning: "RC variations δv, ub, ui, uo and effective clearance per bearing",
};
pub const TOPIC_BEARING_LOADS: Topic = Topic {
    name: "/bearing_loads",
    schema: BEARING_LOADS,
    meaning: "radial bearing load over one period and its mean",
};
pub const TOPIC_THERMAL_FORCES: Topic = Topic {
    name: "/thermal_forces",
    schema: THERMAL_FORCES,
    meaning: "generalised thermal forces per bearing",
};
pub const TOPIC_FLOQUET: Topic = Topic {
    name: "/floquet",
    schema: FLOQUET,
    meaning: "Floquet multipliers and stability",
};
pub const TOPIC_BIFURCATIONS: Topic = Topic {
    name: "/bifurcations",
    schema: BIFURCATION,
    meaning: "located bifurcation points",
};
pub const TOPIC_TRUNCATION: Topic = Topic {
    name: "/truncation",
    schema: TRUNCATION_CHECK,
    meaning: "each located bifurcation and unlocated change of stability re-solved at higher truncation orders: converged, moved or vanished",
};
pub const TOPIC_BRANCHES: Topic = Topic {
    name: "/branches",
    schema: BRANCH_INFO,
    meaning: "branches beside the run's own (e.g. switched to at a period doubling): origin and basis, one message per branch before its points",
};
pub const TOPIC_SCENE: Topic = Topic {
    name: "/scene",
    schema: SCENE_UPDATE,
    meaning: "whirl orbits as line strips along the shaft axis (Foxglove 3D panel)",
};
pub const TOPIC_TF: Topic = Topic {
    name: "/tf",
    schema: FRAME_TRANSFORM,
    meaning: "the scene's frame `rotor` under `world` (static, once at time 0)",
};
pub const TOPIC_LOG: Topic = Topic {
    name: "/log",
    schema: LOG,
    meaning: "run events: start, bifurcations, end status (Foxglove Log panel)",
};

/// All topics, in the order they are registered.
pub const ALL_TOPICS: [Topic; 15] = [
    TOPIC_RUN_INFO,
    TOPIC_SUMMARY,
    TOPIC_HARMONICS,
    TOPIC_ORBITS,
    TOPIC_TEMPERATURES,
    TOPIC_CLEARANCE,
    TOPIC_BEARING_LOADS,
    TOPIC_THERMAL_FORCES,
    TOPIC_FLOQUET,
    TOPIC_BIFURCATIONS,
    TOPIC_TRUNCATION,
    TOPIC_BRANCHES,
    TOPIC_SCENE,
    TOPIC_TF,
    TOPIC_LOG,
];

pub const TOPIC_MAP_INFO: Topic = Topic {
    name: "/map/info",
    schema: MAP_INFO,
    meaning: "operating map: the parameter, the tolerance, the runs and their values (once)",
};
pub const TOPIC_MAP_CURVES: Topic = Topic {
    name: "/map/curves",
    schema: MAP_CURVE,
    meaning: "a curve of one kind of bifurcation in (parameter, ω), one message per curve",
};
pub const TOPIC_MAP_PAIR_ENDS: Topic = Topic {
    name: "/map/pair_ends",
    schema: MAP_PAIR_END,
    meaning: "fold pairs present at one value and gone at the other (a cusp between)",
};
pub const TOPIC_MAP_REGIONS: Topic = Topic {
    name: "/map/regions",
    schema: MAP_REGION,
    meaning: "ω intervals per value with the numbers of stable and unstable responses",
};

/// Every topic of an operating map (`operating_map.mcap`).
pub const MAP_TOPICS: [Topic; 4] = [
    TOPIC_MAP_INFO,
    TOPIC_MAP_CURVES,
    TOPIC_MAP_PAIR_ENDS,
    TOPIC_MAP_REGIONS,
];

pub const TOPIC_TRANSIENT_INFO: Topic = Topic {
    name: "/transient/info",
    schema: TRANSIENT_INFO,
    meaning: "transient run: speed profile, start state, integrator settings (once, at t = 0)",
};
pub const TOPIC_REVOLUTIONS: Topic = Topic {
    name: "/transient/revolution",
    schema: REVOLUTION,
    meaning: "per revolution: speed, RMS and peak amplitude per node, temperatures, clearances, bearing loads",
};
pub const TOPIC_SAMPLES: Topic = Topic {
    name: "/transient/samples",
    schema: SAMPLES,
    meaning: "x, y of every dynamic node, decimated to a few samples per revolution",
};

/// Every topic of a transient recording (beside `/run_info` and `/log`).
pub const TRANSIENT_TOPICS: [Topic; 3] = [TOPIC_TRANSIENT_INFO, TOPIC_REVOLUTIONS, TOPIC_SAMPLES];

/// Names of the MCAP metadata records and attachments.
pub mod names {
    /// Metadata record with tool name/version, model name and hash, creation time.
    pub const METADATA_RUN: &str = "tmrotor.run";
    /// Metadata record with the solver and study settings (key/value).
    pub const METADATA_SETTINGS: &str = "tmrotor.settings";
    /// Metadata record written by `finish`: key `status`.
    pub const METADATA_STATUS: &str = "tmrotor.status";
    /// Media type of the model-file attachment.
    pub const MODEL_MEDIA_TYPE: &str = "application/toml";
    /// Name of the settings attachment (TOML).
    pub const SETTINGS_ATTACHMENT: &str = "settings.toml";
}
