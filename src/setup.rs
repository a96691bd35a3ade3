//! From checked parameter lists to channels: the one place that turns `params::Config` into
//! the settings each machine part takes.

use thiserror::Error;

use crate::channel::door::ListFiles;
use crate::channel::{Channel, ChannelSettings};
use crate::decoder::DecoderSettings;
use crate::geometry::SoftLimits;
use crate::motion::{AxisLimits, PlannerSettings};
use crate::params::runtime::channel_slots;
use crate::params::{ChannelConfig, Config, MAIN_PROGRAMS, SUBROUTINES};
use crate::source::cache::CacheLimits;
use crate::source::loader::Loader;
use crate::source::store::{FsLatency, SearchDir, PATH_MAIN, PATH_SUB};
use crate::vocab::axis::MAX_AXES;

#[derive(Debug, Error)]
pub enum SetupError {
    #[error(
        "axis '{0}': ncchannel knows the axes X Y Z A B C U V W (or a name starting with one, as X1)"
    )]
    UnknownAxis(String),
    #[error("channel {0} does not exist (the start-up list has {1})")]
    NoSuchChannel(u32, usize),
}

/// Axis limits of channel 1, the axes a generated soak program moves (every channel's come
/// from [`channel_axes`]).
pub fn axes(config: &Config) -> Result<Vec<AxisLimits>, SetupError> {
    match config.channels.first() {
        Some(ch) => channel_axes(ch),
        None => Err(SetupError::NoSuchChannel(1, 0)),
    }
}

/// Axis limits of a channel's axes (its one axis table: axis lists or runtime.toml), by
/// `AXIS_LETTERS` index.
pub(crate) fn channel_axes(ch: &ChannelConfig) -> Result<Vec<AxisLimits>, SetupError> {
    let slots = channel_slots(ch.axes.iter().map(|a| a.name.as_str()));
    ch.axes
        .iter()
        .zip(slots)
        .map(|(a, slot)| {
            let index = slot.ok_or_else(|| SetupError::UnknownAxis(a.name.clone()))?;
            Ok(AxisLimits {
                index,
                max_velocity_mm_per_min: a.max_velocity_mm_per_min,
                max_accel_mm_per_s2: a.max_acceleration_mm_per_s2,
                max_jerk_mm_per_s3: a.max_jerk_mm_per_s3,
                rapid_mm_per_min: a.rapid_mm_per_min,
                min_mm: a.soft_limit_min_mm,
                max_mm: a.soft_limit_max_mm,
            })
        })
        .collect()
}

/// Settings of one channel (0-based index in the start-up list).
pub fn channel_settings(
    config: &Config,
    ch: &ChannelConfig,
) -> Result<ChannelSettings, SetupError> {
    let axes = channel_axes(ch)?;
    let mut enabled = [false; MAX_AXES];
    let mut soft_limits_mm = [SoftLimits::default(); MAX_AXES];
    let mut axis_names = crate::decoder::letter_names();
    for (a, c) in axes.iter().zip(&ch.axes) {
        if let Some(n) = crate::lang::block::AxisName::new(c.name.trim()) {
            axis_names[a.index] = n;
        }
    }
    for a in &axes {
        enabled[a.index] = true;
        soft_limits_mm[a.index] = SoftLimits {
            min_mm: a.min_mm,
            max_mm: a.max_mm,
        };
    }
    let rt = &config.runtime;
    let decoder = DecoderSettings {
        blocks_per_tick: rt.decoder.blocks_per_tick.max(1) as usize,
        max_depth: rt.decoder.max_subroutine_depth as usize,
        axes: enabled,
        axis_names,
        zero_offsets: ch.zero_offsets,
        soft_limits_mm,
        implicit: ch.implicit.clone(),
        error_texts: config.error_texts.clone(),
        techno: ch.techno.clone(),
        ext_vars: ch.ext_vars.clone(),
        ..DecoderSettings::default()
    };
    let search_dirs = ch
        .search_paths
        .iter()
        .map(|p| SearchDir {
            dir: p.dir.clone(),
            kinds: (if p.kinds & MAIN_PROGRAMS != 0 {
                PATH_MAIN
            } else {
                0
            }) | (if p.kinds & SUBROUTINES != 0 {
                PATH_SUB
            } else {
                0
            }),
            priority: u32::from(p.priority),
        })
        .collect();
    let c = &ch.decoder.cache;
    Ok(ChannelSettings {
        number: ch.index as u32 + 1,
        decoder,
        queue_capacity: (rt.planner.lookahead_blocks + rt.decoder.buffer_blocks).max(1) as usize,
        axes,
        planner: PlannerSettings {
            lookahead_blocks: rt.planner.lookahead_blocks.max(1) as usize,
            corner_smoothing_s: rt.planner.corner_smoothing_ms / 1000.0,
        },
        search_dirs,
        streaming_prog: ch.streaming_prog_file.clone(),
        cache: CacheLimits {
            enabled: c.enabled,
            max_files: c.max_files as usize,
            max_file_bytes: u64::from(c.max_file_bytes),
        },
        fs_latency: FsLatency::from_us(rt.fs_latency_us, rt.fs_latency_us_per_kib),
        tools: ch.tools.clone(),
        t_selects_d: ch.t_selects_d,
        list_files: ListFiles {
            tool: file_name(ch.tool_list.as_deref()),
            zero_offset: file_name(ch.zero_offset_list.as_deref()),
        },
    })
}

/// A list's file name, as the ADS objects `mc_tool_file_r` / `mc_zero_offset_file_r` show it.
fn file_name(path: Option<&std::path::Path>) -> Option<std::sync::Arc<str>> {
    path.and_then(|p| p.file_name())
        .map(|n| n.to_string_lossy().into())
}

/// Every channel of the configuration, reading and freeing large programs through `loader`.
pub fn channels(
    config: &Config,
    events: bool,
    loader: &Loader,
) -> Result<Vec<Channel>, SetupError> {
    config
        .channels
        .iter()
        .map(|ch| {
            Ok(Channel::new(
                channel_settings(config, ch)?,
                events,
                loader.clone(),
            ))
        })
        .collect()
}
