//! MCAP recording of the published topics, as rosbag2 would record them: profile `ros2`, one
//! schema per message type (encoding `ros2msg`, the standard definition's text), one channel
//! per topic (message encoding `cdr`), log and publish time = simulation time (ns).
//!
//! The file is chunked (uncompressed) and indexed. Chunks hold whole samples: a chunk is
//! closed after the sample that brings it to [`CHUNK_BYTES`], or after the first sample once
//! [`FLUSH_INTERVAL`] of wall time has passed since the last one, so a killed process leaves
//! a file that stream readers read up to its last chunk, with every topic of every sample in
//! it; [`Recorder::finish`] writes the summary and footer.

use crate::frame::Sample;
use crate::Topic;
use mcap::records::MessageHeader;
use mcap::{WriteOptions, Writer};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Size from which a chunk is written out at the end of the sample (bytes, uncompressed).
pub const CHUNK_BYTES: u64 = 512 * 1024;

/// Wall time after which the chunk is written out at the end of the next sample.
pub const FLUSH_INTERVAL: Duration = Duration::from_secs(1);

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
    /// Create `path` with a schema and a channel for each published topic of `topics`
    /// (subscriptions are skipped).
    ///
    /// # Errors
    ///
    /// The file cannot be created or written.
    pub fn create(path: &Path, topics: &[Topic]) -> Result<Recorder, String> {
        let fail = |e: &dyn std::fmt::Display| format!("MCAP file {}: {e}", path.display());
        let file = File::create(path).map_err(|e| fail(&e))?;
        let mut writer = WriteOptions::new()
            .profile("ros2")
            .library(concat!("rkforge-ros ", env!("CARGO_PKG_VERSION")))
            .compression(None)
            .chunk_size(None)
            .create(BufWriter::new(file))
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

    /// Close the last chunk and write the summary (indexes, statistics) and the footer.
    ///
    /// # Errors
    ///
    /// The file cannot be written.
    pub fn finish(mut self) -> Result<PathBuf, String> {
        self.writer
            .finish()
            .map_err(|e| format!("MCAP file {}: {e}", self.path.display()))?;
        Ok(self.path.clone())
    }
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
    use crate::frame::sample;
    use rkforge_core::{Scene, Simulation};

    /// The MCAP bytes of `samples` samples of the scene `text` (at t = 0, then one per step)
    /// and the simulation at the last one; `name` keeps the temporary files of tests apart.
    fn record(text: &str, name: &str, samples: usize) -> (Vec<u8>, Simulation) {
        let scene = Scene::from_str_named(text, "block").unwrap();
        let topics = crate::topics(&scene, "/rkforge").unwrap();
        let mut sim = Simulation::new(&scene).unwrap();
        let path = std::env::temp_dir().join(format!("rkforge_{name}_{}.mcap", std::process::id()));
        let mut rec = Recorder::create(&path, &topics).unwrap();
        rec.write(&sample(&sim)).unwrap();
        for _ in 1..samples {
            sim.step(None).unwrap();
            rec.write(&sample(&sim)).unwrap();
        }
        rec.finish().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        (bytes, sim)
    }

    #[test]
    fn a_recording_reads_back_with_every_message() {
        let text = include_str!("../../scenes/block_forging.toml")
            .replace("particles = [21, 21]", "particles = [5, 5]");
        let (bytes, sim) = record(&text, "rec", 4);
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let stats = summary.stats.unwrap();
        assert_eq!(stats.message_count, 4 * 6);
        assert_eq!(stats.channel_count, 6);
        assert_eq!(stats.schema_count, 5);
        assert!(!summary.chunk_indexes.is_empty());
        let msgs: Vec<_> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(Result::unwrap)
            .collect();
        assert_eq!(msgs.len(), 24);
        let last = msgs.last().unwrap();
        assert_eq!(last.channel.topic, "/clock");
        assert_eq!(last.log_time, crate::frame::nanos(sim.time()));
        let schema = last.channel.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "ros2msg");
        assert_eq!(schema.name, "rosgraph_msgs/msg/Clock");
    }

    /// Chunks close between samples: no sample's messages straddle two chunks, so the
    /// chunks' time ranges (one log time per sample) do not touch.
    #[test]
    fn chunks_hold_whole_samples() {
        let samples = 150;
        let (bytes, _) = record(
            include_str!("../../scenes/block_forging.toml"),
            "chk",
            samples,
        );
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        assert_eq!(summary.stats.unwrap().message_count, samples as u64 * 6);
        let chunks = &summary.chunk_indexes;
        assert!(chunks.len() >= 2, "{} chunks", chunks.len());
        for pair in chunks.windows(2) {
            assert!(pair[0].message_end_time < pair[1].message_start_time);
            assert!(pair[0].uncompressed_size >= CHUNK_BYTES);
            assert!(pair[0].uncompressed_size < CHUNK_BYTES + 64 * 1024);
            assert_eq!(pair[0].message_index_offsets.len(), 6);
        }
    }

    #[test]
    fn a_bad_sample_is_an_error() {
        let path = std::env::temp_dir().join(format!("rkforge_bad_{}.mcap", std::process::id()));
        let scene =
            Scene::from_str_named(include_str!("../../scenes/taylor_bar.toml"), "t").unwrap();
        let topics = crate::topics(&scene, "/rkforge").unwrap();
        let mut rec = Recorder::create(&path, &topics).unwrap();
        let bad = Sample {
            time: 0.0,
            nanos: 0,
            messages: vec![vec![0, 1, 0, 0]],
        };
        let e = rec.write(&bad).unwrap_err();
        assert!(e.contains("1 messages for 5 channels"), "{e}");
        rec.finish().unwrap();
        std::fs::remove_file(&path).unwrap();
    }
}
