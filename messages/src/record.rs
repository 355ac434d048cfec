//! MCAP recording of the published topics, as rosbag2 would record them: profile `ros2`, one
//! schema per message type (encoding `ros2msg`, the standard definition's text), one channel
//! per topic (message encoding `cdr`), log and publish time = simulation time (ns).
//!
//! The file says what made it: a metadata record [`METADATA`] (scene, kinematics, integration
//! rule, resolution, the scene's `[time]` table, rkforge version, the writing program) and the scene file as an
//! attachment, both written first, for a 2D and a 3D scene alike ([`PublishedScene`]); at [`Recorder::finish`] a metadata record [`SUMMARY`]
//! with the run's summary figures (JSON).
//!
//! The file is chunked ([`Compression::Zstd`] by default, or uncompressed) and indexed.
//! Chunks hold whole samples: a chunk is closed after the sample that brings it to
//! [`CHUNK_BYTES`] (uncompressed), or after the first sample once [`FLUSH_INTERVAL`] of wall
//! time has passed since the last one, so a killed process leaves a file that stream readers
//! read up to its last chunk, with every topic of every sample in it;
//! [`Recorder::finish`] writes the summary section and footer.

use crate::frame::Sample;
use crate::{PublishedScene, Topic};
use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, WriteOptions, Writer};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::{Duration, Instant};

/// Size from which a chunk is written out at the end of the sample (bytes, uncompressed).
pub const CHUNK_BYTES: u64 = 512 * 1024;

/// Wall time after which the chunk is written out at the end of the next sample.
pub const FLUSH_INTERVAL: Duration = Duration::from_secs(1);

/// Name of the metadata record that describes the run (written when the file is created).
pub const METADATA: &str = "rkforge";

/// Name of the metadata record with the run's summary (written by [`Recorder::finish`]); its
/// one key is [`SUMMARY_KEY`].
pub const SUMMARY: &str = "rkforge_summary";

/// The key of the summary's JSON text in the [`SUMMARY`] record.
pub const SUMMARY_KEY: &str = "summary_json";

/// Media type of the scene attachment.
const SCENE_MEDIA_TYPE: &str = "application/toml";

/// Chunk compression of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compression {
    /// Zstandard at its default level, on the recording thread.
    #[default]
    Zstd,
    /// Uncompressed chunks.
    None,
}

impl Compression {
    /// The name used on the command line (`zstd`, `none`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Compression::Zstd => "zstd",
            Compression::None => "none",
        }
    }
}

impl FromStr for Compression {
    type Err = String;

    fn from_str(s: &str) -> Result<Compression, String> {
        match s {
            "zstd" => Ok(Compression::Zstd),
            "none" => Ok(Compression::None),
            _ => Err(format!("MCAP compression `{s}`: expected `zstd` or `none`")),
        }
    }
}

/// Where a recording comes from: written into the file's [`METADATA`] record and attachment.
#[derive(Debug, Clone, Copy)]
pub struct Provenance<'a> {
    /// The scene as run, 2D or 3D (its integration rule may differ from the file's, e.g.
    /// after `rkforge run --integration`).
    pub scene: &'a dyn PublishedScene,
    /// The scene file, attached as it is.
    pub scene_file: &'a Path,
    /// The program writing the file, e.g. `rkforge run`.
    pub writer: &'a str,
}

/// Writes samples into an MCAP file.
pub struct Recorder {
    writer: Writer<BufWriter<File>>,
    path: PathBuf,
    channels: Vec<u16>,
    sequence: u32,
    last_flush: Instant,
    /// Bytes of message records in the open chunk.
    pending: u64,
}

impl Recorder {
    /// Create `path`: the [`METADATA`] record and the scene file as an attachment from
    /// `provenance`, then a schema and a channel for each published topic of `topics`
    /// (subscriptions are skipped); chunks compressed with `compression`.
    ///
    /// # Errors
    ///
    /// The scene file cannot be read, or `path` cannot be created or written.
    pub fn create(
        path: &Path,
        topics: &[Topic],
        provenance: &Provenance,
        compression: Compression,
    ) -> Result<Recorder, String> {
        let fail = |e: &dyn std::fmt::Display| format!("MCAP file {}: {e}", path.display());
        let scene_text = std::fs::read(provenance.scene_file).map_err(|e| {
            format!(
                "MCAP file {}: cannot read the scene file {} to attach it: {e}",
                path.display(),
                provenance.scene_file.display()
            )
        })?;
        let file = File::create(path).map_err(|e| fail(&e))?;
        let mut writer = WriteOptions::new()
            .profile("ros2")
            .library(concat!("rkforge-ros ", env!("CARGO_PKG_VERSION")))
            .compression(match compression {
                Compression::Zstd => Some(mcap::Compression::Zstd),
                Compression::None => None,
            })
            // Compress on the recording thread: the solver's workers keep their cores.
            .compression_threads(0)
            .chunk_size(None)
            .create(BufWriter::new(file))
            .map_err(|e| fail(&e))?;
        let name = provenance
            .scene_file
            .file_name()
            .map_or_else(|| "scene.toml".into(), |n| n.to_string_lossy());
        writer
            .attach(&Attachment {
                log_time: 0,
                create_time: 0,
                name: name.clone().into_owned(),
                media_type: SCENE_MEDIA_TYPE.into(),
                data: Cow::Borrowed(&scene_text),
            })
            .map_err(|e| fail(&e))?;
        writer
            .write_metadata(&Metadata {
                name: METADATA.into(),
                metadata: describe(provenance.scene, &name, provenance.writer, compression),
            })
            .map_err(|e| fail(&e))?;
        let mut schemas: BTreeMap<&str, u16> = BTreeMap::new();
        let mut channels = Vec::new();
        for t in topics.iter().filter(|t| t.publish) {
            let schema = match schemas.get(t.message) {
                Some(&id) => id,
                None => {
                    let id = writer
                        .add_schema(t.message, "ros2msg", t.schema.as_bytes())
                        .map_err(|e| fail(&e))?;
                    schemas.insert(t.message, id);
                    id
                }
            };
            let metadata = BTreeMap::from([("offered_qos_profiles".to_owned(), offered_qos(t))]);
            channels.push(
                writer
                    .add_channel(schema, &t.name, "cdr", &metadata)
                    .map_err(|e| fail(&e))?,
            );
        }
        Ok(Recorder {
            writer,
            path: path.to_owned(),
            channels,
            sequence: 0,
            last_flush: Instant::now(),
            pending: 0,
        })
    }

    /// Write the messages of `sample`, logged at its simulation time.
    ///
    /// # Errors
    ///
    /// The sample does not have one message per channel, or the file cannot be written.
    pub fn write(&mut self, sample: &Sample) -> Result<(), String> {
        if sample.messages.len() != self.channels.len() {
            return Err(format!(
                "MCAP file {}: a sample of {} messages for {} channels",
                self.path.display(),
                sample.messages.len(),
                self.channels.len()
            ));
        }
        for (&channel_id, data) in self.channels.iter().zip(&sample.messages) {
            self.sequence = self.sequence.wrapping_add(1);
            let header = MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time: sample.nanos,
                publish_time: sample.nanos,
            };
            self.writer
                .write_to_known_channel(&header, data)
                .map_err(|e| format!("MCAP file {}: {e}", self.path.display()))?;
            // Opcode, record length, channel id, sequence, log and publish times.
            self.pending += 1 + 8 + 2 + 4 + 8 + 8 + data.len() as u64;
        }
        if self.pending >= CHUNK_BYTES || self.last_flush.elapsed() >= FLUSH_INTERVAL {
            self.writer
                .flush()
                .map_err(|e| format!("MCAP file {}: {e}", self.path.display()))?;
            self.last_flush = Instant::now();
            self.pending = 0;
        }
        Ok(())
    }

    /// Close the last chunk, write the [`SUMMARY`] record with `summary` (JSON text) under
    /// [`SUMMARY_KEY`], then the summary section (indexes, statistics) and the footer.
    ///
    /// # Errors
    ///
    /// The file cannot be written.
    pub fn finish(mut self, summary: &str) -> Result<PathBuf, String> {
        let fail = |e: mcap::McapError| format!("MCAP file {}: {e}", self.path.display());
        self.writer
            .write_metadata(&Metadata {
                name: SUMMARY.into(),
                metadata: BTreeMap::from([(SUMMARY_KEY.to_owned(), summary.to_owned())]),
            })
            .map_err(fail)?;
        self.writer.finish().map_err(fail)?;
        Ok(self.path.clone())
    }
}

/// The key-value pairs of the [`METADATA`] record.
fn describe(
    scene: &dyn PublishedScene,
    scene_file: &str,
    writer: &str,
    compression: Compression,
) -> BTreeMap<String, String> {
    [
        ("scene", scene.scene_name().to_owned()),
        ("scene_file", scene_file.to_owned()),
        ("description", scene.scene_description().to_owned()),
        ("kinematics", scene.kinematics_name().to_owned()),
        ("integration", scene.integration_name().to_owned()),
        // The scene's [time] table: end time, step or safety factor, mass scaling.
        (
            "time",
            serde_json::to_string(scene.time_spec()).unwrap_or_else(|e| e.to_string()),
        ),
        ("rkforge_version", env!("CARGO_PKG_VERSION").to_owned()),
        ("writer", writer.to_owned()),
        ("compression", compression.name().to_owned()),
    ]
    .into_iter()
    .chain(scene.grid())
    .map(|(k, v)| (k.to_owned(), v))
    .collect()
}

/// The `offered_qos_profiles` channel metadata rosbag2 writes (YAML), so that `ros2 bag play`
/// offers the same QoS as the node: keep last 10, reliable (1) or best effort (2), transient
/// local (1) or volatile (2).
fn offered_qos(t: &Topic) -> String {
    let reliability = if t.reliable { 1 } else { 2 };
    let durability = if t.latched { 1 } else { 2 };
    let forever = "\n    sec: 2147483647\n    nsec: 4294967295";
    format!(
        "- history: 1\n  depth: 10\n  reliability: {reliability}\n  durability: {durability}\n  deadline:{forever}\n  lifespan:{forever}\n  liveliness: 1\n  liveliness_lease_duration:{forever}\n  avoid_ros_namespace_conventions: false"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Published, Sampler};
    use crate::msgs::{Outputs, RosMessage};
    use rkforge_core::outputs;
    use rkforge_core::outputs::Since;
    use rkforge_core::scene::SolidScene;
    use rkforge_core::solver::SolidSimulation;
    use rkforge_core::{Scene, Simulation};

    /// A temporary directory, removed when it drops, and in it the paths of a recording
    /// `<name>.mcap` and of its scene file `<name>.toml`.
    fn temp(name: &str) -> (tempfile::TempDir, PathBuf, PathBuf) {
        let dir = tempfile::Builder::new()
            .prefix("rkforge_record_")
            .tempdir()
            .unwrap();
        let (mcap, toml) = (
            dir.path().join(format!("{name}.mcap")),
            dir.path().join(format!("{name}.toml")),
        );
        (dir, mcap, toml)
    }

    /// The MCAP bytes of `samples` samples of the scene `text` (at t = 0, then one per step),
    /// the simulation at the last one and where the last one's interval means started; the
    /// scene file is `<name>.toml`.
    fn record(
        text: &str,
        name: &str,
        samples: usize,
        compression: Compression,
    ) -> (Vec<u8>, Simulation, Option<Since>) {
        let scene = Scene::from_str_named(text, "block").unwrap();
        let sim = Simulation::new(&scene).unwrap();
        record_run(&scene, sim, text, name, samples, compression, |s| {
            s.step(None).unwrap();
        })
    }

    /// [`record`] of the simulation `sim` of `scene` (of either kind, read from `text`),
    /// `step` taking it from one sample to the next.
    fn record_run<S: Published>(
        scene: &S::Scene,
        mut sim: S,
        text: &str,
        name: &str,
        samples: usize,
        compression: Compression,
        step: impl Fn(&mut S),
    ) -> (Vec<u8>, S, Option<Since>) {
        let topics = crate::topics(scene, "/rkforge").unwrap();
        let (_dir, path, scene_file) = temp(name);
        std::fs::write(&scene_file, text).unwrap();
        let provenance = Provenance {
            scene,
            scene_file: &scene_file,
            writer: "test",
        };
        let mut rec = Recorder::create(&path, &topics, &provenance, compression).unwrap();
        let mut sampler = Sampler::default();
        let mut since = None;
        rec.write(&sampler.sample(&sim)).unwrap();
        for _ in 1..samples {
            step(&mut sim);
            since = sampler.since().cloned();
            rec.write(&sampler.sample(&sim)).unwrap();
        }
        rec.finish(r#"{"steps": 3}"#).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        (bytes, sim, since)
    }

    /// A 3D run's recording: the topics of a 3D scene (no die fill, no laps), the 3D
    /// register's outputs, and the metadata of a 3D scene (its kinematics, its grid key).
    #[test]
    fn a_3d_recording_reads_back() {
        let text = include_str!("../../scenes/taylor_bar_3d.toml")
            .replace("cells = [8, 4, 60]", "cells = [4, 2, 8]");
        let scene = SolidScene::from_str_named(&text, "bar").unwrap();
        let sim = SolidSimulation::new(&scene).unwrap();
        let (bytes, sim, since) =
            record_run(&scene, sim, &text, "rec3d", 3, Compression::Zstd, |s| {
                s.run_toward(s.time() + 1e-6, u64::MAX, |_, _| true)
                    .unwrap();
            });
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let stats = summary.stats.unwrap();
        assert_eq!((stats.message_count, stats.channel_count), (3 * 7, 7));
        let topics: BTreeMap<&str, &str> = summary
            .channels
            .values()
            .map(|c| (c.topic.as_str(), c.schema.as_ref().unwrap().name.as_str()))
            .collect();
        assert_eq!(topics["/rkforge/workpiece"], "sensor_msgs/msg/PointCloud2");
        assert!(!topics.contains_key("/rkforge/laps") && !topics.contains_key("/rkforge/die_fill"));
        let msgs: Vec<_> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(Result::unwrap)
            .collect();
        let message = msgs.iter().rfind(|m| m.channel.topic == "/rkforge/outputs");
        let o = Outputs::from_cdr(&message.unwrap().data).unwrap();
        let now = outputs::Sample::new(&sim).since(since.as_ref());
        let values: Vec<u64> = outputs::solid_columns(sim.scene())
            .iter()
            .map(|c| c.value(&now).to_bits())
            .collect();
        assert_eq!(
            o.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            values
        );
        assert_eq!(msgs.last().unwrap().log_time, 2000);
        let run = summary
            .metadata_indexes
            .iter()
            .map(|i| mcap::read::metadata(&bytes, i).unwrap())
            .find(|m| m.name == METADATA)
            .unwrap()
            .metadata;
        assert_eq!(run["scene"], "taylor_bar_3d");
        assert_eq!(run["kinematics"], "3d");
        assert_eq!(run["resolution"], "4x2x8");
        assert_eq!(run["resolution_key"], "workpiece.cells");
        assert_eq!(
            run["time"],
            r#"{"end_s":0.00008,"dt_s":null,"dt_safety":0.5}"#
        );
    }

    fn small_block() -> String {
        include_str!("../../scenes/block_forging.toml")
            .replace("particles = [21, 21]", "particles = [5, 5]")
    }

    #[test]
    fn a_recording_reads_back_with_every_message() {
        for compression in [Compression::Zstd, Compression::None] {
            let (bytes, sim, since) = record(&small_block(), "rec", 4, compression);
            let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
            let stats = summary.stats.unwrap();
            assert_eq!(stats.message_count, 4 * 10);
            assert_eq!(stats.channel_count, 10);
            assert_eq!(stats.schema_count, 9);
            assert!(!summary.chunk_indexes.is_empty());
            let expected = match compression {
                Compression::Zstd => "zstd",
                Compression::None => "",
            };
            assert!(summary
                .chunk_indexes
                .iter()
                .all(|c| c.compression == expected));
            let msgs: Vec<_> = mcap::MessageStream::new(&bytes)
                .unwrap()
                .map(Result::unwrap)
                .collect();
            assert_eq!(msgs.len(), 40);
            // The register's outputs read back: every column, with the last sample's values.
            let message = msgs.iter().rfind(|m| m.channel.topic == "/rkforge/outputs");
            let o = Outputs::from_cdr(&message.unwrap().data).unwrap();
            let now = outputs::Sample::new(&sim).since(since.as_ref());
            let register = outputs::columns(sim.scene());
            assert_eq!(o.names.len(), register.len());
            for (k, c) in register.iter().enumerate() {
                assert_eq!(o.names[k], c.name);
                assert_eq!(o.units[k], c.unit());
                assert_eq!(o.values[k].to_bits(), c.value(&now).to_bits(), "{}", c.name);
            }
            let last = msgs.last().unwrap();
            assert_eq!(last.channel.topic, "/clock");
            assert_eq!(last.log_time, crate::frame::nanos(sim.time()));
            let schema = last.channel.schema.as_ref().unwrap();
            assert_eq!(schema.encoding, "ros2msg");
            assert_eq!(schema.name, "rosgraph_msgs/msg/Clock");
        }
    }

    #[test]
    fn the_file_names_its_scene_and_summary_and_attaches_the_scene() {
        let text = small_block();
        let (bytes, _, _) = record(&text, "meta", 2, Compression::Zstd);
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let records: BTreeMap<String, BTreeMap<String, String>> = summary
            .metadata_indexes
            .iter()
            .map(|i| {
                let m = mcap::read::metadata(&bytes, i).unwrap();
                (m.name, m.metadata)
            })
            .collect();
        let run = &records[METADATA];
        assert_eq!(run["scene"], "block_forging");
        assert_eq!(run["integration"], "q2");
        assert_eq!(run["resolution"], "5x5");
        assert_eq!(run["kinematics"], "plane_strain");
        assert_eq!(run["rkforge_version"], env!("CARGO_PKG_VERSION"));
        assert_eq!(run["compression"], "zstd");
        assert_eq!(
            run["time"],
            r#"{"end_s":0.015,"dt_s":1e-6,"dt_safety":0.5}"#
        );
        assert_eq!(
            records[SUMMARY],
            BTreeMap::from([(SUMMARY_KEY.to_owned(), r#"{"steps": 3}"#.to_owned())])
        );
        assert_eq!(summary.attachment_indexes.len(), 1);
        let a = mcap::read::attachment(&bytes, &summary.attachment_indexes[0]).unwrap();
        assert_eq!(a.name, "meta.toml");
        assert_eq!(a.media_type, "application/toml");
        assert_eq!(&*a.data, text.as_bytes());
        // A mass-scaled scene says so in the same record.
        let scaled = text.replace("[time]\n", "[time]\nmass_scaling = { factor = 100.0 }\n");
        let (scaled_bytes, _, _) = record(&scaled, "meta_scaled", 2, Compression::Zstd);
        let scaled_summary = mcap::Summary::read(&scaled_bytes).unwrap().unwrap();
        let time = scaled_summary
            .metadata_indexes
            .iter()
            .map(|i| mcap::read::metadata(&scaled_bytes, i).unwrap())
            .find(|m| m.name == METADATA)
            .map(|m| m.metadata["time"].clone());
        assert_eq!(
            time.as_deref(),
            Some(r#"{"end_s":0.015,"dt_s":1e-6,"dt_safety":0.5,"mass_scaling":{"factor":100.0}}"#)
        );
    }

    /// Chunks close between samples: no sample's messages straddle two chunks, so the
    /// chunks' time ranges (one log time per sample) do not touch.
    #[test]
    fn chunks_hold_whole_samples() {
        let samples = 150;
        for compression in [Compression::Zstd, Compression::None] {
            let (bytes, _, _) = record(
                include_str!("../../scenes/block_forging.toml"),
                "chk",
                samples,
                compression,
            );
            let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
            assert_eq!(summary.stats.unwrap().message_count, samples as u64 * 10);
            let chunks = &summary.chunk_indexes;
            assert!(chunks.len() >= 2, "{} chunks", chunks.len());
            for pair in chunks.windows(2) {
                assert!(pair[0].message_end_time < pair[1].message_start_time);
                assert!(pair[0].uncompressed_size >= CHUNK_BYTES);
                assert!(pair[0].uncompressed_size < CHUNK_BYTES + 64 * 1024);
                assert_eq!(pair[0].message_index_offsets.len(), 10);
            }
        }
    }

    #[test]
    fn compression_names_parse() {
        assert_eq!("zstd".parse(), Ok(Compression::Zstd));
        assert_eq!("none".parse(), Ok(Compression::None));
        let e = "lz4".parse::<Compression>().unwrap_err();
        assert!(e.contains("`lz4`: expected `zstd` or `none`"), "{e}");
    }

    #[test]
    fn a_missing_scene_file_is_named() {
        let scene =
            Scene::from_str_named(include_str!("../../scenes/taylor_bar.toml"), "t").unwrap();
        let topics = crate::topics(&scene, "/rkforge").unwrap();
        let provenance = Provenance {
            scene: &scene,
            scene_file: Path::new("no/such/scene.toml"),
            writer: "test",
        };
        let (_dir, path, _) = temp("missing");
        let e = Recorder::create(&path, &topics, &provenance, Compression::Zstd)
            .err()
            .unwrap();
        assert!(
            e.contains("cannot read the scene file no/such/scene.toml"),
            "{e}"
        );
        assert!(!path.exists());
    }

    #[test]
    fn a_bad_sample_is_an_error() {
        let text = include_str!("../../scenes/taylor_bar.toml");
        let scene = Scene::from_str_named(text, "t").unwrap();
        let topics = crate::topics(&scene, "/rkforge").unwrap();
        let (_dir, path, scene_file) = temp("bad");
        std::fs::write(&scene_file, text).unwrap();
        let provenance = Provenance {
            scene: &scene,
            scene_file: &scene_file,
            writer: "test",
        };
        let mut rec = Recorder::create(&path, &topics, &provenance, Compression::None).unwrap();
        let bad = Sample {
            time: 0.0,
            nanos: 0,
            messages: vec![vec![0, 1, 0, 0]],
        };
        let e = rec.write(&bad).unwrap_err();
        assert!(e.contains("1 messages for 9 channels"), "{e}");
        rec.finish("{}").unwrap();
    }
}
