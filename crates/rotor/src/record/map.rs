//! The recording of an operating map (`tmrotor campaign map`): the curves of bifurcations
//! in (p, ω), the fold-pair ends and the coexistence regions, written to and read from an
//! MCAP file on the topics [`super::schema::MAP_TOPICS`] through the record layer's
//! conversion ([`super::convert::map_to_pb`]) and channel registration
//! ([`super::mcap_sink::Channels`]), like every other recording.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use prost::Message;

use super::ReadError;
use super::RecordError;
use super::convert::{
    map_curve_from_pb, map_info_from_pb, map_pair_end_from_pb, map_region_from_pb, map_to_pb,
};
use super::mcap_sink::{Channels, writer_options};
use super::pb::tmrotor::v1 as pb;
use super::schema::{
    TOPIC_MAP_CURVES, TOPIC_MAP_INFO, TOPIC_MAP_PAIR_ENDS, TOPIC_MAP_REGIONS, Topic,
};
use crate::stability::BifurcationKind;

/// One run of the campaign a map was built from: its name, its value of the parameter and
/// its recording (relative to the campaign directory).
#[derive(Clone, Debug, PartialEq)]
pub struct MapRun {
    pub name: String,
    pub value: f64,
    pub recording: String,
}

/// A curve of one kind of bifurcation through the runs, as (p, ω) in order of `p`.
#[derive(Clone, Debug, PartialEq)]
pub struct MapCurve {
    pub id: usize,
    pub kind: BifurcationKind,
    pub points: Vec<(f64, f64)>,
}

/// A fold pair present at one grid value and gone at the next: a cusp lies between.
#[derive(Clone, Debug, PartialEq)]
pub struct PairEnd {
    /// The grid value where the pair exists.
    pub p_with: f64,
    /// The neighbouring grid value where it does not.
    pub p_without: f64,
    /// The pair's mean ω where it exists (rad/s).
    pub omega: f64,
    /// The run where it exists.
    pub run: String,
    /// Bisection sweeps that narrowed the bracket; 0: the grid's.
    pub refined: usize,
}

/// A run of ω cells at one `p` with the same numbers of stable and unstable responses.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    pub p: f64,
    pub omega_from: f64,
    pub omega_to: f64,
    pub stable: usize,
    pub unstable: usize,
}

/// What an operating map's recording holds.
#[derive(Clone, Debug, PartialEq)]
pub struct MapRecord {
    /// The parameter (a settings key, or `set.<path>`).
    pub param: String,
    /// Largest ω distance of two points joined into a curve (rad/s).
    pub omega_tolerance: f64,
    pub runs: Vec<MapRun>,
    pub curves: Vec<MapCurve>,
    pub pair_ends: Vec<PairEnd>,
    pub regions: Vec<Region>,
}

/// Writes `map` to `path` (built in memory, then through a temporary file renamed into
/// place, [`super::output::write_atomic`]).
pub fn write_map(map: &MapRecord, path: &Path) -> Result<(), RecordError> {
    let mcap_err = |source: mcap::McapError| RecordError::Mcap {
        path: path.to_path_buf(),
        source,
    };
    let mut writer = writer_options()
        .create(Cursor::new(Vec::new()))
        .map_err(mcap_err)?;
    let mut channels = Channels::default();
    let mut publish = |topic: Topic, seq: usize, bytes: Vec<u8>| {
        let channel_id = channels.id(&mut writer, topic)?;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: seq as u32,
            log_time: seq as u64,
            publish_time: seq as u64,
        };
        writer.write_to_known_channel(&header, &bytes)
    };
    let m = map_to_pb(map);
    publish(TOPIC_MAP_INFO, 0, m.info.encode_to_vec()).map_err(mcap_err)?;
    for (k, c) in m.curves.iter().enumerate() {
        publish(TOPIC_MAP_CURVES, k, c.encode_to_vec()).map_err(mcap_err)?;
    }
    for (k, e) in m.pair_ends.iter().enumerate() {
        publish(TOPIC_MAP_PAIR_ENDS, k, e.encode_to_vec()).map_err(mcap_err)?;
    }
    for (k, r) in m.regions.iter().enumerate() {
        publish(TOPIC_MAP_REGIONS, k, r.encode_to_vec()).map_err(mcap_err)?;
    }
    writer.finish().map_err(mcap_err)?;
    let bytes = writer.into_inner().into_inner();
    super::output::write_atomic(path, &bytes).map_err(|source| RecordError::Create {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads an operating map's recording. A topic that does not belong to a map, a message
/// that does not decode or a file without `/map/info` is an error naming the file.
pub fn read_map(path: &Path) -> Result<MapRecord, ReadError> {
    let file: PathBuf = path.to_path_buf();
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        file: file.clone(),
        source,
    })?;
    let corrupt = |reason: String| ReadError::Corrupt {
        file: file.clone(),
        reason,
    };
    if !bytes.starts_with(mcap::MAGIC) {
        return Err(ReadError::NotMcap {
            file,
            reason: "it does not start with the MCAP magic bytes".into(),
        });
    }
    let stream = mcap::MessageStream::new(&bytes).map_err(|e| ReadError::NotMcap {
        file: file.clone(),
        reason: e.to_string(),
    })?;
    let mut info: Option<MapRecord> = None;
    let (mut curves, mut pair_ends, mut regions) = (Vec::new(), Vec::new(), Vec::new());
    for message in stream {
        let message = message.map_err(|e| corrupt(e.to_string()))?;
        let topic = message.channel.topic.as_str();
        let data = &message.data[..];
        let decode_err = |e: prost::DecodeError| corrupt(format!("{topic}: {e}"));
        match topic {
            t if t == TOPIC_MAP_INFO.name => {
                info = Some(map_info_from_pb(
                    pb::MapInfo::decode(data).map_err(decode_err)?,
                ));
            }
            t if t == TOPIC_MAP_CURVES.name => {
                let m = pb::MapCurve::decode(data).map_err(decode_err)?;
                curves.push(map_curve_from_pb(m).map_err(|e| corrupt(format!("{topic}: {e}")))?);
            }
            t if t == TOPIC_MAP_PAIR_ENDS.name => {
                let m = pb::MapPairEnd::decode(data).map_err(decode_err)?;
                pair_ends.push(map_pair_end_from_pb(m));
            }
            t if t == TOPIC_MAP_REGIONS.name => {
                let m = pb::MapRegion::decode(data).map_err(decode_err)?;
                regions.push(map_region_from_pb(m));
            }
            other => {
                return Err(ReadError::Foreign {
                    file,
                    reason: format!("topic {other} does not belong to an operating map"),
                });
            }
        }
    }
    let Some(mut map) = info else {
        return Err(ReadError::Foreign {
            file,
            reason: "no /map/info: not an operating map".into(),
        });
    };
    map.curves = curves;
    map.pair_ends = pair_ends;
    map.regions = regions;
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_survives_its_recording() {
        let map = MapRecord {
            param: "flow_l_min".into(),
            omega_tolerance: 25.0,
            runs: vec![MapRun {
                name: "q1".into(),
                value: 1.0,
                recording: "q1.mcap".into(),
            }],
            curves: vec![MapCurve {
                id: 3,
                kind: BifurcationKind::SaddleNode,
                points: vec![(1.0, 520.0), (2.0, 530.5)],
            }],
            pair_ends: vec![PairEnd {
                p_with: 2.0,
                p_without: 3.0,
                omega: 525.0,
                run: "q2".into(),
                refined: 2,
            }],
            regions: vec![Region {
                p: 1.0,
                omega_from: 500.0,
                omega_to: 510.0,
                stable: 2,
                unstable: 1,
            }],
        };
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("map.mcap");
        write_map(&map, &path).expect("write");
        assert_eq!(read_map(&path).expect("read"), map);
        std::fs::write(&path, b"not mcap").expect("overwrite");
        assert!(matches!(read_map(&path), Err(ReadError::NotMcap { .. })));
    }
}
