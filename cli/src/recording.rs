//! `rkforge run --mcap`: the ROS 2 topics of `rkforge-ros` (namespace `/rkforge`) recorded
//! at every history sample of a run of either kind ([`rkforge_messages::frame::Published`]:
//! a 2D or a 3D simulation), with the signal flag that stops the run there and lets it
//! finish its files.

use rkforge_messages::frame::{Published, Sampler};
use rkforge_messages::record::{Compression, Provenance, Recorder};
use rkforge_messages::PublishedScene;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Where and how to record MCAP.
pub struct McapOptions {
    /// The MCAP file.
    pub path: PathBuf,
    /// The scene file, attached to the recording.
    pub scene_file: PathBuf,
    /// Chunk compression.
    pub compression: Compression,
}

/// The MCAP recording of a run and the signal flag that stops it.
pub struct Mcap {
    recorder: Recorder,
    /// The outputs' interval means since the last record.
    sampler: Sampler,
    stop: Arc<AtomicBool>,
}

impl Mcap {
    /// Create the file for a run of `scene` (2D or 3D) and install the handler of SIGINT
    /// and SIGTERM.
    ///
    /// # Errors
    ///
    /// A tool name cannot name a topic, the file cannot be created, or the handler cannot
    /// be installed.
    pub fn start(opts: &McapOptions, scene: &dyn PublishedScene) -> Result<Mcap, String> {
        let topics = rkforge_messages::topics(scene, "/rkforge")?;
        let provenance = Provenance {
            scene,
            scene_file: &opts.scene_file,
            writer: "rkforge run",
        };
        Ok(Mcap {
            recorder: Recorder::create(&opts.path, &topics, &provenance, opts.compression)?,
            sampler: Sampler::default(),
            stop: rkforge_messages::signals::stop_flag()?,
        })
    }

    /// Record the messages of `sim` now.
    ///
    /// # Errors
    ///
    /// The file cannot be written.
    pub fn record<S: Published>(&mut self, sim: &S) -> Result<(), String> {
        self.recorder.write(&self.sampler.sample(sim))
    }

    /// The failure to report if a signal asked the run to stop; `time` (s) is the run's
    /// time now.
    pub fn interrupted(&self, time: f64) -> Option<String> {
        self.stop
            .load(Ordering::SeqCst)
            .then(|| format!("interrupted by a signal at t = {time:e} s"))
    }

    /// Write the summary record (`summary`, summary.json's text) and close the file.
    ///
    /// # Errors
    ///
    /// The file cannot be written.
    pub fn finish(self, summary: &str) -> Result<(), String> {
        self.recorder.finish(summary).map(|_| ())
    }
}
