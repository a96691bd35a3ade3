//! The COM task (AMS port 553): platform, channel and axis objects at the kernel's addresses,
//! and the object description table that lists them.
//!
//! Addresses, types and sizes are the ISG kernel's (object dump `SamWieHTWG/web-api`
//! `examples/example1-hello-cnc/cnc_objects.csv`, groups there index-based; Beckhoff infosys
//! "TF5200 ADS access to CNC"), names as TwinSharp looks them up (`kimblad/TwinSharp`
//! `TwinSharp/CNC/CncPlatform.cs`, `CncChannel.cs`, `AxisStatus.cs`).
//!
//! Groups: channel `0x120100 + ch` (logical) or `0x20100 + ch` (index-based; with channels
//! numbered 1..n both name the same channel); channel axis k at offset `0x10000·k + element`;
//! platform axis k at `(0x120200 + k, element)` or, as TwinSharp reads it,
//! `(0x120200, 0x10000·k + element)`. Platform objects answer in any channel group (the
//! kernel: "the first channel drives platform data"). What ncchannel does not model is
//! absent (0x703), never a made-up value.

use super::backend::{CncBackend, DeviceError, HmiOp, Live, ObjectEncoder, Op, Source, Status};
use super::description::{self, Access, AdsType, ObjectInfo};
use super::hli::{Hli, HmiRequest};
use super::result::AdsResult;
use crate::channel::{Mode, State};

/// AMS port of the COM task.
pub const PORT: u16 = 553;
/// Channel objects, logical addressing: `GROUP_CHANNEL + ch`.
pub(crate) const GROUP_CHANNEL: u32 = 0x120100;
/// Channel objects, index-based addressing.
pub(crate) const GROUP_CHANNEL_INDEX: u32 = 0x20100;
/// Platform axes: `GROUP_PLATFORM_AXIS + axis`.
pub(crate) const GROUP_PLATFORM_AXIS: u32 = 0x120200;
pub(crate) const GROUP_PLATFORM_AXIS_INDEX: u32 = 0x20200;
/// Object description table: `GROUP_DESCRIPTION + ch` (0 lists channel 1).
pub(crate) const GROUP_DESCRIPTION: u32 = 0x130100;
pub(crate) const GROUP_DESCRIPTION_INDEX: u32 = 0x30100;
/// Channel-axis and TwinSharp platform-axis offsets: `AXIS_STRIDE · axis + element`.
pub(crate) const AXIS_STRIDE: u32 = 0x10000;
/// Offsets of ncchannel's own channel objects (`ncc_*`): the ISG object dump's channel objects
/// end at 0x3118 and channel axes start at 0x10000 (docs/ads.md).
pub const VENDOR_OFFSETS: std::ops::RangeInclusive<u32> = 0x8000..=0x8FFF;

/// Longest program name accepted by `mcm_command_parameter_w` (its STRING(300) buffer).
pub(crate) const MAX_PARAMETER_BYTES: usize = 300;
/// 0.1 µm per mm: positions on the wire.
const TENTH_UM_PER_MM: f64 = 10_000.0;
/// µm/s per mm/min: feeds on the wire.
const UM_PER_S_PER_MM_PER_MIN: f64 = 1000.0 / 60.0;
/// Axes per channel ncchannel can configure (`vocab::axis::MAX_AXES`).
const MAX_AXES_PER_CHANNEL: u32 = crate::vocab::axis::MAX_AXES as u32;

const SRC_DUMP: &str = "ISG object dump";
const SRC_TS: &str = "ISG object dump; TwinSharp";
const SRC_NCC: &str = "ncchannel";

/// Where an object lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scope {
    Platform,
    Channel,
    /// Offset `0x10000·k + element` in the channel group; name has `{k}`.
    ChannelAxis,
    /// Group `0x120200 + k`; name has `{k}`.
    PlatformAxis,
}

/// What an object means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Field {
    TickCounter,
    CycleTime,
    Version,
    AxisCount,
    ChannelCount,
    AxisMax,
    SpindleMax,
    ChannelMax,
    TimeMin,
    TimeMax,
    TimeAct,
    TimeAvg,
    TimeReset,
    SingleBlockCommand,
    SingleBlockActive,
    OptionalStop,
    SkipCommand,
    SkipActive,
    OverrideCommand,
    OverrideActive,
    SearchFileOffset,
    BlockCount,
    ActiveBlockNumber,
    ActiveFileName,
    ActiveFileOffset,
    ActiveProgramName,
    CommandFeed,
    ActiveFeed,
    ErrorMessage,
    PlatformErrorMessage,
    FeedHoldCommand,
    FeedHold,
    SlopeBufLevel,
    ProgramCount,
    SearchDistance,
    SearchCovered,
    SearchAutoReturn,
    SearchDeviationMax,
    SearchNoHold,
    SearchBreakpoint,
    Message,
    /// The active tool ID (`mc_active_tool_id_*`): basic = the active D (TF5200 "Programming
    /// commands and variables": the D word's value is the basic tool number); ncchannel has
    /// no sister or variant tools.
    ToolId,
    ToolBasic,
    ToolSister,
    ToolSisterValid,
    /// The file names of the channel's zero-offset and tool lists (read only: the lists are
    /// read at start-up).
    ZeroOffsetFile,
    ToolFile,
    ChannelNumber,
    ChannelAxes,
    ExecutionModeCommand,
    ExecutionModeActive,
    SearchType,
    SearchBlockCount,
    SearchBlockNumber,
    IpoBufLevel,
    Stream,
    McmActiveMode,
    McmActive,
    McmActiveState,
    McmToMode,
    McmToState,
    McmFromMode,
    McmFromState,
    McmParameter,
    Hold,
    Resume,
    Reset,
    NccStreamFill,
    NccBlocksExecuted,
    NccPositions,
    AxisLogicalNo,
    AxisName,
    AxisType,
    AxisState,
    AxisChannel,
    AxisPosition,
    AxisPositionHr,
    AxisPositionPcs,
    AxisPositionPcsHr,
}

/// One object of the table.
struct Def {
    scope: Scope,
    element: u32,
    name: &'static str,
    ty: AdsType,
    size: u32,
    access: Access,
    unit: &'static str,
    source: &'static str,
    field: Field,
}

#[allow(clippy::too_many_arguments)]
const fn d(
    scope: Scope,
    element: u32,
    name: &'static str,
    ty: AdsType,
    size: u32,
    access: Access,
    unit: &'static str,
    source: &'static str,
    field: Field,
) -> Def {
    Def {
        scope,
        element,
        name,
        ty,
        size,
        access,
        unit,
        source,
        field,
    }
}

use Access::{Read as R, Write as W};
use AdsType::*;
use Field as F;
use Scope::{Channel as CH, ChannelAxis as CA, Platform as PL, PlatformAxis as PA};

/// Every COM object ncchannel serves, in listing order.
#[rustfmt::skip]
static TABLE: &[Def] = &[
    d(PL, 0x251, "cnc_tick_counter_r", Dword, 4, R, "CNC ticks", SRC_TS, F::TickCounter),
    d(PL, 0x252, "cnc_cycle_time_r", Dword, 4, R, "µs", SRC_TS, F::CycleTime),
    d(PL, 0x253, "cnc_version_r", String, 24, R, "", SRC_TS, F::Version),
    d(PL, 0x254, "cnc_number_of_axis_r", Dword, 4, R, "", SRC_TS, F::AxisCount),
    d(PL, 0x255, "cnc_number_of_channel_r", Word, 2, R, "", SRC_TS, F::ChannelCount),
    d(PL, 0x257, "cnc_error_message_r", String, 1330, R, "channel 1's last error", SRC_DUMP, F::PlatformErrorMessage),
    d(PL, 0x258, "cnc_time_geo_min", Dword, 4, R, "0.1 µs", SRC_DUMP, F::TimeMin),
    d(PL, 0x259, "cnc_time_geo_max", Dword, 4, R, "0.1 µs", SRC_DUMP, F::TimeMax),
    d(PL, 0x25A, "cnc_time_geo_act", Dword, 4, R, "0.1 µs", SRC_DUMP, F::TimeAct),
    d(PL, 0x261, "cnc_time_reset", Trigger, 0, W, "", SRC_DUMP, F::TimeReset),
    d(PL, 0x262, "cnc_number_of_axis_max_r", Dword, 4, R, "", SRC_TS, F::AxisMax),
    d(PL, 0x263, "cnc_number_of_spindle_max_r", Dword, 4, R, "", SRC_TS, F::SpindleMax),
    d(PL, 0x264, "cnc_number_of_channel_max_r", Word, 2, R, "", SRC_TS, F::ChannelMax),
    d(PL, 0x288, "cnc_time_geo_avg", Dword, 4, R, "0.1 µs", SRC_DUMP, F::TimeAvg),
    d(CH, 0x01, "mc_command_single_block_w", Bool, 1, W, "", SRC_TS, F::SingleBlockCommand),
    d(CH, 0x02, "mc_command_single_block_r", Bool, 1, R, "", SRC_DUMP, F::SingleBlockCommand),
    d(CH, 0x03, "mc_active_single_block_r", Bool, 1, R, "", SRC_TS, F::SingleBlockActive),
    d(CH, 0x07, "mc_command_M01_stop_enable_w", Bool, 1, W, "", SRC_TS, F::OptionalStop),
    d(CH, 0x08, "mc_command_M01_stop_enable_r", Bool, 1, R, "", SRC_DUMP, F::OptionalStop),
    d(CH, 0x04, "mc_command_block_ignore_w", Dword, 4, W, "skip levels 1–10 = bits 0–9", SRC_TS, F::SkipCommand),
    d(CH, 0x05, "mc_command_block_ignore_r", Dword, 4, R, "skip levels 1–10 = bits 0–9", SRC_TS, F::SkipCommand),
    d(CH, 0x06, "mc_active_block_ignore_r", Dword, 4, R, "skip levels 1–10 = bits 0–9", SRC_DUMP, F::SkipActive),
    d(CH, 0x09, "mc_command_feedrate_override_w", Word, 2, W, "0.1 %", SRC_TS, F::OverrideCommand),
    d(CH, 0x0A, "mc_command_feedrate_override_r", Word, 2, R, "0.1 %", SRC_TS, F::OverrideCommand),
    d(CH, 0x0B, "mc_command_file_offset_r", Dint, 4, R, "bytes", SRC_DUMP, F::SearchFileOffset),
    d(CH, 0x0C, "mc_active_feedrate_override_r", Word, 2, R, "0.1 %", SRC_TS, F::OverrideActive),
    d(CH, 0x0D, "mc_block_count_r", Dword, 4, R, "NC lines decoded since the start", SRC_TS, F::BlockCount),
    d(CH, 0x0E, "mc_active_blocknumber_r", Dword, 4, R, "N number", SRC_DUMP, F::ActiveBlockNumber),
    d(CH, 0x0F, "mc_active_file_name_r", String, 84, R, "", SRC_DUMP, F::ActiveFileName),
    d(CH, 0x10, "mc_active_file_offset_r", Dint, 4, R, "bytes", SRC_DUMP, F::ActiveFileOffset),
    d(CH, 0x11, "mc_command_file_offset_w", Dint, 4, W, "bytes", SRC_TS, F::SearchFileOffset),
    d(CH, 0x12, "mc_active_program_name_r", String, 84, R, "", SRC_DUMP, F::ActiveProgramName),
    d(CH, 0x13, "mc_command_feedrate_r", Lreal, 8, R, "µm/s", SRC_TS, F::CommandFeed),
    d(CH, 0x14, "mc_active_feedrate_r", Lreal, 8, R, "µm/s", SRC_TS, F::ActiveFeed),
    d(CH, 0x15, "mc_command_feedhold_r", Bool, 1, R, "", SRC_DUMP, F::FeedHoldCommand),
    d(CH, 0x16, "mc_feedhold_channel_w", Bool, 1, W, "TRUE holds, FALSE releases", SRC_DUMP, F::FeedHold),
    d(CH, 0x19, "mc_active_tool_id_r", ToolId, 16, R, "basic = active D", SRC_DUMP, F::ToolId),
    d(CH, 0x1A, "mc_active_tool_id_basic_r", Dint, 4, R, "active D", SRC_DUMP, F::ToolBasic),
    d(CH, 0x1B, "mc_active_tool_id_sister_r", Dint, 4, R, "0: no sister tools", SRC_DUMP, F::ToolSister),
    d(CH, 0x1C, "mc_active_tool_id_variant_r", Dint, 4, R, "0: no variants", SRC_DUMP, F::ToolSister),
    d(CH, 0x1D, "mc_active_tool_id_sister_val_r", Bool, 1, R, "FALSE", SRC_DUMP, F::ToolSisterValid),
    d(CH, 0x1E, "mc_active_tool_id_variant_val_r", Bool, 1, R, "FALSE", SRC_DUMP, F::ToolSisterValid),
    d(CH, 0x1F, "mc_message_r", String, 120, R, "last #MSG text", SRC_DUMP, F::Message),
    d(CH, 0x26, "mc_error_message_r", String, 1330, R, "", SRC_DUMP, F::ErrorMessage),
    d(CH, 0x2B, "mc_actual_logical_axes_number_r", Dword, 4, R, "", SRC_DUMP, F::ChannelAxes),
    d(CH, 0x2C, "mc_channel_number_r", Word, 2, R, "", SRC_DUMP, F::ChannelNumber),
    d(CH, 0x2D, "mc_zero_offset_file_r", String, 84, R, "file name, empty: none", SRC_DUMP, F::ZeroOffsetFile),
    d(CH, 0x2F, "mc_tool_file_r", String, 84, R, "file name, empty: none", SRC_DUMP, F::ToolFile),
    d(CH, 0x3F, "mc_command_execution_mode_w", Dint, 4, W, "0 standard, 1 block search", SRC_TS, F::ExecutionModeCommand),
    d(CH, 0x40, "mc_command_execution_mode_r", Dint, 4, R, "0 standard, 1 block search", SRC_TS, F::ExecutionModeCommand),
    d(CH, 0x41, "mc_active_execution_mode_r", Dint, 4, R, "0 standard, 1 block search", SRC_TS, F::ExecutionModeActive),
    d(CH, 0x44, "mc_cmd_bs_distance_prog_start_w", Lreal, 8, W, "0.1 µm", SRC_TS, F::SearchDistance),
    d(CH, 0x45, "mc_cmd_bs_distance_prog_start_r", Lreal, 8, R, "0.1 µm", SRC_TS, F::SearchDistance),
    d(CH, 0x49, "mc_cmd_bs_type_w", Word, 2, W, "1 offset, 3 counter, 4 N", SRC_TS, F::SearchType),
    d(CH, 0x4A, "mc_cmd_bs_covered_distance_w", Lreal, 8, W, "0.1 % of the block", SRC_TS, F::SearchCovered),
    d(CH, 0x4B, "mc_cmd_bs_auto_return_w", Bool, 1, W, "", SRC_TS, F::SearchAutoReturn),
    d(CH, 0x4C, "mc_cmd_bs_deviation_max_w", Dword, 4, W, "0.1 µm", SRC_TS, F::SearchDeviationMax),
    d(CH, 0x50, "mc_cmd_bs_pos_start_offset_w", Dint, 4, W, "bytes", SRC_DUMP, F::SearchFileOffset),
    d(CH, 0x5E, "mc_cmd_bs_intern_block_count_w", Dword, 4, W, "", SRC_DUMP, F::SearchBlockCount),
    d(CH, 0x5F, "mc_cmd_bs_block_number_w", Dword, 4, W, "N number", SRC_TS, F::SearchBlockNumber),
    d(CH, 0x61, "mc_cmd_bs_type_r", Word, 2, R, "1 offset, 3 counter, 4 N", SRC_TS, F::SearchType),
    d(CH, 0x62, "mc_cmd_bs_covered_distance_r", Lreal, 8, R, "0.1 % of the block", SRC_TS, F::SearchCovered),
    d(CH, 0x63, "mc_cmd_bs_auto_return_r", Bool, 1, R, "", SRC_TS, F::SearchAutoReturn),
    d(CH, 0x64, "mc_cmd_bs_deviation_max_r", Dword, 4, R, "0.1 µm", SRC_TS, F::SearchDeviationMax),
    d(CH, 0x68, "mc_cmd_bs_pos_start_offset_r", Dint, 4, R, "bytes", SRC_DUMP, F::SearchFileOffset),
    d(CH, 0x76, "mc_cmd_bs_intern_block_count_r", Dword, 4, R, "", SRC_DUMP, F::SearchBlockCount),
    d(CH, 0x77, "mc_cmd_bs_block_number_r", Dword, 4, R, "N number", SRC_TS, F::SearchBlockNumber),
    d(CH, 0x79, "mc_cmd_bs_no_hold_at_restart_w", Bool, 1, W, "", SRC_TS, F::SearchNoHold),
    d(CH, 0x7A, "mc_cmd_bs_no_hold_at_restart_r", Bool, 1, R, "", SRC_TS, F::SearchNoHold),
    d(CH, 0x7B, "mc_cmd_bs_breakpoint_position_w", Lreal, 8, W, "0.1 µm from the program start", SRC_TS, F::SearchBreakpoint),
    d(CH, 0x7C, "mc_cmd_bs_breakpoint_position_r", Lreal, 8, R, "0.1 µm from the program start", SRC_TS, F::SearchBreakpoint),
    d(CH, 0x7E, "mc_ipo_buf_level", Dword, 4, R, "blocks", SRC_DUMP, F::IpoBufLevel),
    d(CH, 0x7F, "mc_slope_buf_level", Dword, 4, R, "blocks waiting for the lookahead", SRC_DUMP, F::SlopeBufLevel),
    d(CH, 0x90, "mc_program_stream_w", String, 1208, W, "ASCII, whole CR LF lines ≤ 992 bytes", SRC_TS, F::Stream),
    d(CH, 0x44F, "mc_program_count_r", Dword, 4, R, "programs run to their end", SRC_DUMP, F::ProgramCount),
    d(CH, 0x101, "mcm_active_mode_r", Dint, 4, R, "mode", SRC_DUMP, F::McmActiveMode),
    d(CH, 0x103, "mcm_active_r", ModeState, 8, R, "mode, state", SRC_DUMP, F::McmActive),
    d(CH, 0x104, "mcm_command_to_mode_w", Dint, 4, W, "mode", SRC_DUMP, F::McmToMode),
    d(CH, 0x105, "mcm_command_to_state_w", Dint, 4, W, "state", SRC_DUMP, F::McmToState),
    d(CH, 0x106, "mcm_command_from_mode_w", Dint, 4, W, "mode, 0 = any", SRC_DUMP, F::McmFromMode),
    d(CH, 0x107, "mcm_command_from_state_w", Dint, 4, W, "state, 0 = any", SRC_DUMP, F::McmFromState),
    d(CH, 0x108, "mcm_command_parameter_w", String, 300, W, "program name", SRC_DUMP, F::McmParameter),
    d(CH, 0x109, "mcm_active_state_r", Dint, 4, R, "state", SRC_DUMP, F::McmActiveState),
    d(CH, 0x11D, "mcm_standby_reset_w", Trigger, 0, W, "", SRC_DUMP, F::Reset),
    d(CH, 0x136, "mcm_automatic_stop_w", Trigger, 0, W, "", SRC_DUMP, F::Hold),
    d(CH, 0x137, "mcm_automatic_resume_w", Trigger, 0, W, "", SRC_DUMP, F::Resume),
    d(CH, 0x13C, "mcm_automatic_reset_w", Trigger, 0, W, "", SRC_DUMP, F::Reset),
    d(CH, 0x155, "mcm_mdi_reset_w", Trigger, 0, W, "", SRC_DUMP, F::Reset),
    d(CH, 0x8001, "ncc_stream_fill_r", Dword2, 8, R, "bytes used, bytes free", SRC_NCC, F::NccStreamFill),
    d(CH, 0x8002, "ncc_blocks_executed_r", Lword, 8, R, "blocks since the channel started", SRC_NCC, F::NccBlocksExecuted),
    d(CH, 0x8003, "ncc_positions_mm_r", LrealArray, 0, R, "mm per axis", SRC_NCC, F::NccPositions),
    d(CA, 0x01, "mc_axis_{k}_logical_no_r", Word, 2, R, "", SRC_TS, F::AxisLogicalNo),
    d(CA, 0x02, "mc_axis_{k}_name_r", String, 16, R, "", SRC_TS, F::AxisName),
    d(CA, 0x03, "mc_axis_{k}_type_r", Word, 2, R, "1 translator, 2 rotator", SRC_TS, F::AxisType),
    d(CA, 0x06, "mc_ax_{k}_active_position_pcs_r", Dint, 4, R, "0.1 µm", SRC_TS, F::AxisPositionPcs),
    d(CA, 0x07, "mc_ax_{k}_curr_position_pcs_r", Dint, 4, R, "0.1 µm", SRC_TS, F::AxisPositionPcs),
    d(CA, 0x09, "mc_axis_{k}_state_r", Word, 2, R, "1 ready, 3 active, 5 hold, 7 error", SRC_TS, F::AxisState),
    d(CA, 0x35, "mc_ax_{k}_active_position_pcs_hr_r", Lreal, 8, R, "0.1 µm", SRC_DUMP, F::AxisPositionPcsHr),
    d(CA, 0x36, "mc_ax_{k}_curr_position_pcs_hr_r", Lreal, 8, R, "0.1 µm", SRC_DUMP, F::AxisPositionPcsHr),
    d(PA, 0x01, "ac_{k}_type_r", Word, 2, R, "1 translator, 2 rotator", SRC_TS, F::AxisType),
    d(PA, 0x02, "ac_{k}_active_position_acs_r", Dint, 4, R, "0.1 µm", SRC_TS, F::AxisPosition),
    d(PA, 0x03, "ac_{k}_current_position_acs_r", Dint, 4, R, "0.1 µm", SRC_TS, F::AxisPosition),
    d(PA, 0x09, "ac_{k}_axis_name_r", String, 16, R, "", SRC_TS, F::AxisName),
    d(PA, 0x0C, "ac_{k}_state_r", Word, 2, R, "1 ready, 3 active, 5 hold, 7 error", SRC_TS, F::AxisState),
    d(PA, 0x0F, "ac_{k}_channel_nr_r", Word, 2, R, "", SRC_TS, F::AxisChannel),
    d(PA, 0x30, "ac_{k}_active_position_acs_hr_r", Lreal, 8, R, "0.1 µm", SRC_DUMP, F::AxisPositionHr),
];

/// An address resolved to one object of the table.
struct Target<'a> {
    def: &'a Def,
    /// 1-based channel (channel objects and channel axes; 0 for platform objects).
    ch: u16,
    /// 1-based axis (platform or channel axis), 0 otherwise.
    axis: u32,
}

/// A platform axis: the `index`-th (0-based) axis of channel `ch`.
struct PlatformAxis {
    ch: u16,
    index: usize,
}

/// Platform axes are the channels' axes in channel order (ncchannel has no axes outside
/// channels and no axis exchange).
fn platform_axes(source: &mut dyn Source) -> Result<Vec<PlatformAxis>, AdsResult> {
    let mut out = Vec::new();
    for ch in 1..=source.channel_count() {
        let n = source.status(ch).map_err(AdsResult::from)?.positions.len();
        out.extend((0..n).map(|index| PlatformAxis { ch, index }));
    }
    Ok(out)
}

fn channel_in(group: u32, base: u32, base_index: u32) -> Option<u32> {
    if (base..base + 0x100).contains(&group) {
        Some(group - base)
    } else if (base_index..base_index + 0x100).contains(&group) {
        Some(group - base_index)
    } else {
        None
    }
}

fn find(scope: Scope, element: u32) -> Option<&'static Def> {
    TABLE
        .iter()
        .find(|d| d.scope == scope && d.element == element)
}

/// Which object `(group, offset)` names, or 0x702/0x703.
fn resolve(channels: u16, group: u32, offset: u32) -> Result<Target<'static>, AdsResult> {
    let count = u32::from(channels);
    if let Some(ch) = channel_in(group, GROUP_CHANNEL, GROUP_CHANNEL_INDEX) {
        if ch > count {
            return Err(AdsResult::INVALID_GROUP);
        }
        if offset >= AXIS_STRIDE {
            let (axis, element) = (offset / AXIS_STRIDE, offset % AXIS_STRIDE);
            let def = find(Scope::ChannelAxis, element).ok_or(AdsResult::INVALID_OFFSET)?;
            if ch == 0 {
                return Err(AdsResult::INVALID_GROUP);
            }
            return Ok(Target {
                def,
                ch: ch as u16,
                axis,
            });
        }
        if let Some(def) = find(Scope::Platform, offset) {
            return Ok(Target {
                def,
                ch: 0,
                axis: 0,
            });
        }
        if ch == 0 {
            return Err(AdsResult::INVALID_GROUP);
        }
        let def = find(Scope::Channel, offset).ok_or(AdsResult::INVALID_OFFSET)?;
        return Ok(Target {
            def,
            ch: ch as u16,
            axis: 0,
        });
    }
    if let Some(k) = channel_in(group, GROUP_PLATFORM_AXIS, GROUP_PLATFORM_AXIS_INDEX) {
        // TwinSharp AxisStatus.cs: constant group, axis in the offset's high word.
        let (axis, element) = if k == 0 {
            (offset / AXIS_STRIDE, offset % AXIS_STRIDE)
        } else {
            (k, offset)
        };
        let def = find(Scope::PlatformAxis, element).ok_or(AdsResult::INVALID_OFFSET)?;
        return Ok(Target { def, ch: 0, axis });
    }
    Err(AdsResult::INVALID_GROUP)
}

/// Every object a listing of channel `ch` holds (platform, channel `ch`, its axes, all
/// platform axes), names unique. `ch` 0 lists channel 1.
pub fn objects(backend: &dyn CncBackend, ch: u16) -> Result<Vec<ObjectInfo>, AdsResult> {
    let ch = ch.max(1);
    let mut live = Live::new(backend);
    let axes = platform_axes(&mut live)?;
    let view = live.status(ch).map_err(AdsResult::from)?;
    let group = GROUP_CHANNEL + u32::from(ch);
    let mut out = Vec::with_capacity(TABLE.len() + 16 * axes.len());
    for def in TABLE {
        let info = |name: std::string::String, group: u32, offset: u32, size: u32| ObjectInfo {
            port: PORT,
            group,
            offset,
            name,
            ty: def.ty,
            size,
            access: def.access,
            unit: def.unit,
            source: def.source,
        };
        match def.scope {
            Scope::Platform => out.push(info(
                def.name.into(),
                GROUP_CHANNEL + 1,
                def.element,
                def.size,
            )),
            Scope::Channel => {
                let size = match def.field {
                    Field::NccPositions => 8 * view.positions.len() as u32,
                    _ => def.size,
                };
                out.push(info(def.name.into(), group, def.element, size));
            }
            Scope::ChannelAxis => {
                for k in 1..=view.positions.len() as u32 {
                    let name = def.name.replace("{k}", &k.to_string());
                    out.push(info(name, group, AXIS_STRIDE * k + def.element, def.size));
                }
            }
            Scope::PlatformAxis => {
                for k in 1..=axes.len() as u32 {
                    let name = def.name.replace("{k}", &k.to_string());
                    out.push(info(name, GROUP_PLATFORM_AXIS + k, def.element, def.size));
                }
            }
        }
    }
    Ok(out)
}

fn dev(e: DeviceError) -> AdsResult {
    e.into()
}

/// A fixed-size value: at least its size must be asked for; exactly its size is answered.
fn fixed(bytes: Vec<u8>, length: u32) -> Result<Vec<u8>, AdsResult> {
    if (length as usize) < bytes.len() {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(bytes)
}

/// A string object: its text NUL-padded to its buffer size, cut to the length asked for.
fn text(s: &str, size: u32, length: u32) -> Vec<u8> {
    let size = size as usize;
    let mut b = vec![0u8; size];
    let n = s.len().min(size.saturating_sub(1));
    b[..n].copy_from_slice(&s.as_bytes()[..n]);
    b.truncate(length as usize);
    b
}

fn tenth_um(mm: f64) -> f64 {
    mm * TENTH_UM_PER_MM
}

/// Saturating conversion of 0.1 µm to the kernel's SGN32 positions.
fn tenth_um_i32(mm: f64) -> i32 {
    tenth_um(mm).round().clamp(i32::MIN as f64, i32::MAX as f64) as i32
}

fn duration_tenth_us(d: std::time::Duration) -> u32 {
    u32::try_from(d.as_nanos() / 100).unwrap_or(u32::MAX)
}

/// Axis state as the kernel numbers it (TwinSharp `AxisState`: 1 READY, 3 ACTIVE, 5 HOLD,
/// 7 ERROR), from the channel the axis belongs to.
fn axis_state(v: &Status) -> u16 {
    match v.state {
        State::Active => 3,
        State::Hold => 5,
        State::Error => 7,
        _ => 1,
    }
}

/// Axis type as the kernel numbers it (TwinSharp `AxisStatus.cs`: 1 translator, 2 rotator,
/// 4 spindle): A, B and C are ncchannel's rotary axes (degrees), X, Y and Z linear.
fn axis_type(letter: char) -> u16 {
    match letter {
        'A' | 'B' | 'C' => 2,
        _ => 1,
    }
}

/// A channel's last error as the error-message objects show it: number and text.
fn error_text(v: &Status) -> std::string::String {
    v.last_error
        .as_ref()
        .map(|(code, msg)| format!("{code} {msg}"))
        .unwrap_or_default()
}

fn override_tenths(pct: f64) -> u16 {
    (pct * 10.0).round().clamp(0.0, 2000.0) as u16
}

/// ADS Read on port 553.
pub fn read(
    backend: &dyn CncBackend,
    group: u32,
    offset: u32,
    length: u32,
) -> Result<Vec<u8>, AdsResult> {
    if let Some(ch) = channel_in(group, GROUP_DESCRIPTION, GROUP_DESCRIPTION_INDEX) {
        if ch > u32::from(backend.channel_count()) {
            return Err(AdsResult::INVALID_GROUP);
        }
        return description::read_table(&objects(backend, ch as u16)?, offset, length);
    }
    let mut live = Live::new(backend);
    encoder(&mut live, group, offset, length)?(&mut live)
}

/// The encoder of object `(group, offset)`, read `length` bytes at a time: what [`read`] runs
/// once and a notification evaluated in the cycle runs every due tick (`machine::watch`).
/// Which object, channel and axis it is is settled here, from `source` (the axes are fixed
/// while serving); the encoder reads only the status it shows. `Err` for an address that
/// names no readable object and for the description table (read whole, by [`read`]).
pub(crate) fn encoder(
    source: &mut dyn Source,
    group: u32,
    offset: u32,
    length: u32,
) -> Result<ObjectEncoder, AdsResult> {
    if channel_in(group, GROUP_DESCRIPTION, GROUP_DESCRIPTION_INDEX).is_some() {
        return Err(AdsResult::ACCESS_DENIED);
    }
    let channels = source.channel_count();
    let t = resolve(channels, group, offset)?;
    if !t.def.access.readable() {
        return Err(AdsResult::ACCESS_DENIED);
    }
    let def = t.def;
    Ok(match def.scope {
        Scope::Platform if def.field == Field::AxisCount => Box::new(move |s: &mut dyn Source| {
            fixed(
                (platform_axes(s)?.len() as u32).to_le_bytes().to_vec(),
                length,
            )
        }),
        Scope::Platform => Box::new(move |s: &mut dyn Source| {
            platform_from_status(s.status(1).map_err(dev)?, channels, def, length)
        }),
        Scope::Channel => {
            let ch = t.ch;
            Box::new(move |s: &mut dyn Source| {
                read_channel(s.status(ch).map_err(dev)?, ch, def, length)
            })
        }
        Scope::ChannelAxis => {
            let ch = t.ch;
            let axes = source.status(ch).map_err(dev)?.positions.len();
            let i = (t.axis as usize)
                .checked_sub(1)
                .filter(|&i| i < axes)
                .ok_or(AdsResult::INVALID_OFFSET)?;
            let logical = platform_axes(source)?
                .iter()
                .position(|a| a.ch == ch && a.index == i)
                .map_or(0, |p| p + 1) as u16;
            Box::new(move |s: &mut dyn Source| {
                read_axis(s.status(ch).map_err(dev)?, ch, i, logical, def, length)
            })
        }
        Scope::PlatformAxis => {
            let axes = platform_axes(source)?;
            let a = (t.axis as usize)
                .checked_sub(1)
                .and_then(|i| axes.get(i))
                .ok_or(AdsResult::INVALID_OFFSET)?;
            let (ch, index, logical) = (a.ch, a.index, t.axis as u16);
            Box::new(move |s: &mut dyn Source| {
                read_axis(s.status(ch).map_err(dev)?, ch, index, logical, def, length)
            })
        }
    })
}

/// The active D as the kernel's DINT tool number.
fn active_d(v: &Status) -> i32 {
    i32::try_from(v.active_tool.0).unwrap_or(i32::MAX)
}

/// A platform object other than the axis count, from channel 1's status ("the first channel
/// drives platform data", infosys 312764171) and the number of channels.
fn platform_from_status(
    v: &Status,
    channels: u16,
    def: &Def,
    length: u32,
) -> Result<Vec<u8>, AdsResult> {
    let t = v.cycle_times;
    let bytes = match def.field {
        Field::TickCounter => (v.tick as u32).to_le_bytes().to_vec(),
        Field::CycleTime => u32::try_from(v.period.as_micros())
            .unwrap_or(u32::MAX)
            .to_le_bytes()
            .to_vec(),
        Field::Version => {
            return Ok(text(
                &format!("ncchannel {}", env!("CARGO_PKG_VERSION")),
                def.size,
                length,
            ))
        }
        Field::ChannelCount | Field::ChannelMax => channels.to_le_bytes().to_vec(),
        Field::AxisMax => (MAX_AXES_PER_CHANNEL * u32::from(channels))
            .to_le_bytes()
            .to_vec(),
        Field::SpindleMax => 0u32.to_le_bytes().to_vec(),
        Field::TimeMin => duration_tenth_us(t.min).to_le_bytes().to_vec(),
        Field::TimeMax => duration_tenth_us(t.max).to_le_bytes().to_vec(),
        Field::TimeAct => duration_tenth_us(t.last).to_le_bytes().to_vec(),
        Field::TimeAvg => duration_tenth_us(t.mean()).to_le_bytes().to_vec(),
        // "The first channel drives platform data" (infosys 312764171): ncchannel has no
        // errors outside its channels.
        Field::PlatformErrorMessage => return Ok(text(&error_text(v), def.size, length)),
        _ => return Err(AdsResult::ACCESS_DENIED),
    };
    fixed(bytes, length)
}

fn read_channel(v: &Status, ch: u16, def: &Def, length: u32) -> Result<Vec<u8>, AdsResult> {
    let h = &v.hmi;
    let active = v.active_block.as_ref();
    let programmed_um_s = v.modal.feed_mm_per_min * UM_PER_S_PER_MM_PER_MIN;
    let bytes = match def.field {
        Field::SingleBlockCommand => vec![u8::from(h.single_block)],
        Field::SingleBlockActive => vec![u8::from(h.single_block)],
        Field::OptionalStop => vec![u8::from(h.optional_stop)],
        Field::SkipCommand | Field::SkipActive => h.skip_levels.to_le_bytes().to_vec(),
        Field::OverrideCommand | Field::OverrideActive => {
            override_tenths(v.override_pct).to_le_bytes().to_vec()
        }
        Field::SearchFileOffset => h.search.file_offset.to_le_bytes().to_vec(),
        Field::BlockCount => (v.block_counter as u32).to_le_bytes().to_vec(),
        Field::ActiveBlockNumber => active.and_then(|a| a.n).unwrap_or(0).to_le_bytes().to_vec(),
        Field::ActiveFileName => return Ok(text(active.map_or("", |a| &a.prog), def.size, length)),
        Field::ActiveFileOffset => active
            .map_or(0, |a| i32::try_from(a.offset).unwrap_or(i32::MAX))
            .to_le_bytes()
            .to_vec(),
        Field::ActiveProgramName => {
            return Ok(text(v.program.as_deref().unwrap_or(""), def.size, length))
        }
        Field::CommandFeed => programmed_um_s.to_le_bytes().to_vec(),
        Field::ActiveFeed => (programmed_um_s * v.override_pct / 100.0)
            .to_le_bytes()
            .to_vec(),
        Field::ErrorMessage => return Ok(text(&error_text(v), def.size, length)),
        Field::FeedHoldCommand => vec![u8::from(h.feed_hold)],
        Field::SlopeBufLevel => (v.queued_blocks as u32).to_le_bytes().to_vec(),
        // A UNS32 counter: it wraps, as the kernel's counters do.
        Field::ProgramCount => (v.programs_ended as u32).to_le_bytes().to_vec(),
        Field::SearchDistance => h.search.distance_prog_start_tenth_um.to_le_bytes().to_vec(),
        Field::SearchCovered => h.search.covered_distance_per_mil.to_le_bytes().to_vec(),
        Field::SearchAutoReturn => vec![u8::from(h.search.auto_return)],
        Field::SearchDeviationMax => h.search.deviation_max_tenth_um.to_le_bytes().to_vec(),
        Field::SearchNoHold => vec![u8::from(h.search.no_hold_at_restart)],
        Field::SearchBreakpoint => h.search.breakpoint_tenth_um.to_le_bytes().to_vec(),
        Field::Message => return Ok(text(v.message.as_deref().unwrap_or(""), def.size, length)),
        Field::ChannelAxes => (v.positions.len() as u32).to_le_bytes().to_vec(),
        Field::ToolId => {
            let mut b = vec![0u8; 16];
            b[..4].copy_from_slice(&active_d(v).to_le_bytes());
            b
        }
        Field::ToolBasic => active_d(v).to_le_bytes().to_vec(),
        Field::ToolSister => 0i32.to_le_bytes().to_vec(),
        Field::ToolSisterValid => vec![0],
        Field::ZeroOffsetFile => {
            return Ok(text(
                v.list_files.zero_offset.as_deref().unwrap_or(""),
                def.size,
                length,
            ))
        }
        Field::ToolFile => {
            return Ok(text(
                v.list_files.tool.as_deref().unwrap_or(""),
                def.size,
                length,
            ))
        }
        Field::ChannelNumber => ch.to_le_bytes().to_vec(),
        Field::ExecutionModeCommand => h.execution_mode.to_le_bytes().to_vec(),
        Field::ExecutionModeActive => i32::from(v.searching).to_le_bytes().to_vec(),
        Field::SearchType => h.search.kind.to_le_bytes().to_vec(),
        Field::SearchBlockCount => h.search.block_count.to_le_bytes().to_vec(),
        Field::SearchBlockNumber => h.search.block_number.to_le_bytes().to_vec(),
        Field::IpoBufLevel => (v.ipo_blocks as u32).to_le_bytes().to_vec(),
        Field::McmActiveMode => (v.mode as i32).to_le_bytes().to_vec(),
        Field::McmActiveState => (v.state as i32).to_le_bytes().to_vec(),
        Field::McmActive => [
            (v.mode as i32).to_le_bytes(),
            (v.state as i32).to_le_bytes(),
        ]
        .concat(),
        Field::NccStreamFill => [
            (v.stream_used as u32).to_le_bytes(),
            (v.stream_free as u32).to_le_bytes(),
        ]
        .concat(),
        Field::NccBlocksExecuted => v.blocks.to_le_bytes().to_vec(),
        Field::NccPositions => v
            .positions
            .iter()
            .flat_map(|(_, p)| p.to_le_bytes())
            .collect(),
        _ => return Err(AdsResult::ACCESS_DENIED),
    };
    fixed(bytes, length)
}

fn read_axis(
    v: &Status,
    ch: u16,
    index: usize,
    logical: u16,
    def: &Def,
    length: u32,
) -> Result<Vec<u8>, AdsResult> {
    let (letter, mm) = *v.positions.get(index).ok_or(AdsResult::INVALID_OFFSET)?;
    let bytes = match def.field {
        Field::AxisLogicalNo => logical.to_le_bytes().to_vec(),
        Field::AxisName => return Ok(text(&letter.to_string(), def.size, length)),
        Field::AxisType => axis_type(letter).to_le_bytes().to_vec(),
        Field::AxisState => axis_state(v).to_le_bytes().to_vec(),
        Field::AxisChannel => ch.to_le_bytes().to_vec(),
        Field::AxisPosition => tenth_um_i32(mm).to_le_bytes().to_vec(),
        Field::AxisPositionHr => tenth_um(mm).to_le_bytes().to_vec(),
        Field::AxisPositionPcs => {
            let (_, pcs) = *v
                .pcs_positions
                .get(index)
                .ok_or(AdsResult::INVALID_OFFSET)?;
            tenth_um_i32(pcs).to_le_bytes().to_vec()
        }
        Field::AxisPositionPcsHr => {
            let (_, pcs) = *v
                .pcs_positions
                .get(index)
                .ok_or(AdsResult::INVALID_OFFSET)?;
            tenth_um(pcs).to_le_bytes().to_vec()
        }
        _ => return Err(AdsResult::ACCESS_DENIED),
    };
    fixed(bytes, length)
}

/// A text argument: up to the first NUL, at most `max` bytes, UTF-8, trimmed.
pub(crate) fn text_arg(data: &[u8], max: usize) -> Result<&str, AdsResult> {
    let end = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let text = &data[..end];
    if text.len() > max {
        return Err(AdsResult::INVALID_SIZE);
    }
    std::str::from_utf8(text)
        .map(str::trim)
        .map_err(|_| AdsResult::INVALID_DATA)
}

/// An integer argument: 1, 2 or 4 bytes little-endian (clients write the type they have).
fn int_arg(data: &[u8]) -> Result<i64, AdsResult> {
    match *data {
        [a] => Ok(i64::from(a)),
        [a, b] => Ok(i64::from(i16::from_le_bytes([a, b]))),
        [a, b, c, d] => Ok(i64::from(i32::from_le_bytes([a, b, c, d]))),
        _ => Err(AdsResult::INVALID_SIZE),
    }
}

fn uint_arg(data: &[u8]) -> Result<u32, AdsResult> {
    match *data {
        [a] => Ok(u32::from(a)),
        [a, b] => Ok(u32::from(u16::from_le_bytes([a, b]))),
        [a, b, c, d] => Ok(u32::from_le_bytes([a, b, c, d])),
        _ => Err(AdsResult::INVALID_SIZE),
    }
}

fn bool_arg(data: &[u8]) -> Result<bool, AdsResult> {
    match data {
        [b] | [b, 0] | [b, 0, 0, 0] => Ok(*b != 0),
        _ => Err(AdsResult::INVALID_SIZE),
    }
}

/// An LREAL argument (8 bytes) in `0..=max`: distances and shares are never negative.
fn distance_arg(data: &[u8], max: f64) -> Result<f64, AdsResult> {
    let bytes: [u8; 8] = data.try_into().map_err(|_| AdsResult::INVALID_SIZE)?;
    let v = f64::from_le_bytes(bytes);
    if v.is_finite() && (0.0..=max).contains(&v) {
        Ok(v)
    } else {
        Err(AdsResult::INVALID_DATA)
    }
}

fn i32_arg(data: &[u8]) -> Result<i32, AdsResult> {
    i32::try_from(int_arg(data)?).map_err(|_| AdsResult::INVALID_DATA)
}

/// ADS Write on port 553. Mode and state commands go to the PLC instead when its HLI unit
/// operates them ([`Hli::redirect`]).
pub fn write(
    backend: &dyn CncBackend,
    hli: &Hli,
    group: u32,
    offset: u32,
    data: &[u8],
) -> Result<(), AdsResult> {
    if channel_in(group, GROUP_DESCRIPTION, GROUP_DESCRIPTION_INDEX).is_some() {
        return Err(AdsResult::ACCESS_DENIED);
    }
    let t = resolve(backend.channel_count(), group, offset)?;
    if !t.def.access.writable() {
        return Err(AdsResult::ACCESS_DENIED);
    }
    let ch = t.ch;
    match t.def.field {
        Field::TimeReset => unit(backend.command(1, Op::Hmi(HmiOp::ResetCycleTimes))),
        Field::Stream => write_stream(backend, ch, data),
        Field::SingleBlockCommand
        | Field::OptionalStop
        | Field::SkipCommand
        | Field::OverrideCommand
        | Field::ExecutionModeCommand => write_switch(backend, ch, t.def.field, data),
        Field::SearchType
        | Field::SearchFileOffset
        | Field::SearchBlockCount
        | Field::SearchBlockNumber
        | Field::SearchDistance
        | Field::SearchCovered
        | Field::SearchAutoReturn
        | Field::SearchDeviationMax
        | Field::SearchNoHold
        | Field::SearchBreakpoint => write_search(backend, ch, t.def.field, data),
        Field::FeedHold => write_feed_hold(backend, ch, data),
        Field::McmToMode
        | Field::McmToState
        | Field::McmFromMode
        | Field::McmFromState
        | Field::McmParameter => write_mcm(backend, hli, ch, t.def.field, data),
        Field::Hold | Field::Resume | Field::Reset => {
            write_hold_resume_reset(backend, ch, t.def.field, data)
        }
        _ => Err(AdsResult::ACCESS_DENIED),
    }
}

/// A backend command's outcome as an ADS result (the device error's code).
fn unit(r: Result<(), DeviceError>) -> Result<(), AdsResult> {
    r.map_err(dev)
}

/// Write step: stream bytes go to the channel's stream; its refusal is the answer.
fn write_stream(backend: &dyn CncBackend, ch: u16, data: &[u8]) -> Result<(), AdsResult> {
    let r = super::backend::write_stream(backend, ch, data);
    if r.is_ok() {
        Ok(())
    } else {
        Err(r)
    }
}

/// Write step: HMI switches (single block, optional stop, skip levels, override,
/// execution mode), each argument range-checked before the backend sees it.
fn write_switch(
    backend: &dyn CncBackend,
    ch: u16,
    field: Field,
    data: &[u8],
) -> Result<(), AdsResult> {
    match field {
        Field::SingleBlockCommand => {
            unit(backend.command(ch, Op::Hmi(HmiOp::SingleBlock(bool_arg(data)?))))
        }
        Field::OptionalStop => {
            unit(backend.command(ch, Op::Hmi(HmiOp::OptionalStop(bool_arg(data)?))))
        }
        Field::SkipCommand => {
            let mask = uint_arg(data)?;
            if mask & !0x3FF != 0 {
                return Err(AdsResult::INVALID_DATA);
            }
            unit(backend.command(ch, Op::Hmi(HmiOp::SkipLevels(mask))))
        }
        Field::OverrideCommand => {
            let tenths = uint_arg(data)?;
            if tenths > 2000 {
                return Err(AdsResult::INVALID_DATA);
            }
            unit(backend.command(ch, Op::SetOverride(f64::from(tenths) / 10.0)))
        }
        Field::ExecutionModeCommand => {
            unit(backend.command(ch, Op::Hmi(HmiOp::ExecutionMode(i32_arg(data)?))))
        }
        _ => Err(AdsResult::ACCESS_DENIED),
    }
}

/// Write step: one field of the block search command; the argument is checked first, then
/// the channel's current search command is read, changed and written back whole.
fn write_search(
    backend: &dyn CncBackend,
    ch: u16,
    field: Field,
    data: &[u8],
) -> Result<(), AdsResult> {
    let search = |f: &dyn Fn(&mut crate::channel::SearchCommand)| -> Result<(), AdsResult> {
        let mut s = backend.status(ch).map_err(dev)?.hmi.search;
        f(&mut s);
        unit(backend.command(ch, Op::Hmi(HmiOp::Search(s))))
    };
    match field {
        Field::SearchType => {
            let kind = uint_arg(data)?;
            let kind = u16::try_from(kind).map_err(|_| AdsResult::INVALID_DATA)?;
            if !matches!(kind, 0 | 1 | 3 | 4) {
                return Err(AdsResult::INVALID_DATA);
            }
            search(&|s| s.kind = kind)
        }
        Field::SearchFileOffset => {
            let o = i32_arg(data)?;
            search(&|s| s.file_offset = o)
        }
        Field::SearchBlockCount => {
            let n = uint_arg(data)?;
            search(&|s| s.block_count = n)
        }
        Field::SearchBlockNumber => {
            let n = uint_arg(data)?;
            search(&|s| s.block_number = n)
        }
        Field::SearchDistance => {
            let d = distance_arg(data, f64::MAX)?;
            search(&|s| s.distance_prog_start_tenth_um = d)
        }
        Field::SearchCovered => {
            // TwinSharp `BlockSearch.cs`: "Value range: [0.0 to 1000.0]".
            let p = distance_arg(data, 1000.0)?;
            search(&|s| s.covered_distance_per_mil = p)
        }
        Field::SearchBreakpoint => {
            let d = distance_arg(data, f64::MAX)?;
            search(&|s| s.breakpoint_tenth_um = d)
        }
        Field::SearchAutoReturn => {
            let on = bool_arg(data)?;
            search(&|s| s.auto_return = on)
        }
        Field::SearchNoHold => {
            let on = bool_arg(data)?;
            search(&|s| s.no_hold_at_restart = on)
        }
        Field::SearchDeviationMax => {
            let d = uint_arg(data)?;
            search(&|s| s.deviation_max_tenth_um = d)
        }
        _ => Err(AdsResult::ACCESS_DENIED),
    }
}

/// Write step: the HLI mode/state command interface (MCM); mode, state and program
/// requests go to the PLC when its HLI unit operates them ([`Hli::redirect`]).
fn write_mcm(
    backend: &dyn CncBackend,
    hli: &Hli,
    ch: u16,
    field: Field,
    data: &[u8],
) -> Result<(), AdsResult> {
    match field {
        Field::McmToMode => {
            let m = i32_arg(data)?;
            match hli.redirect(ch, HmiRequest::ToMode(m)) {
                Some(r) => r,
                None => refused(hli, ch, backend.command(ch, Op::CommandMode(m))),
            }
        }
        Field::McmToState => {
            let s = i32_arg(data)?;
            match hli.redirect(ch, HmiRequest::ToState(s)) {
                Some(r) => r,
                None => refused(hli, ch, backend.command(ch, Op::CommandState(s))),
            }
        }
        Field::McmFromMode | Field::McmFromState => {
            // "Optional; 0 = no significance" (HLI docs): ncchannel checks nothing here.
            let v = i32_arg(data)?;
            if v == 0 || Mode::from_i32(v).is_some() || State::from_i32(v).is_some() || v == 15 {
                Ok(())
            } else {
                Err(AdsResult::INVALID_DATA)
            }
        }
        Field::McmParameter => {
            let name = text_arg(data, MAX_PARAMETER_BYTES)?;
            if name.is_empty() {
                return Err(AdsResult::INVALID_SIZE);
            }
            match hli.redirect(ch, HmiRequest::Parameter(name)) {
                Some(r) => r,
                None => unit(backend.command(ch, Op::SetProgram(name.to_string()))),
            }
        }
        _ => Err(AdsResult::ACCESS_DENIED),
    }
}

/// A mode or state command's result; one the channel's mode and state do not allow also
/// posts the kernel's 270061 in the PLC's `mc_error` (as the kernel reports a refused
/// transition whoever asked for it) and answers 0x707.
fn refused(hli: &Hli, ch: u16, r: Result<(), DeviceError>) -> Result<(), AdsResult> {
    if r == Err(DeviceError::Refused) {
        hli.note_refusal(ch);
    }
    unit(r)
}

/// Write step: `mc_feedhold_channel_w`, one BOOL; the channel decides (a TRUE with no
/// program running is 0x707, a state command its state does not allow).
fn write_feed_hold(backend: &dyn CncBackend, ch: u16, data: &[u8]) -> Result<(), AdsResult> {
    unit(backend.command(ch, Op::Hmi(HmiOp::FeedHold(bool_arg(data)?))))
}

/// Write step: hold, resume and reset take no argument beyond an optional 4-byte word.
fn write_hold_resume_reset(
    backend: &dyn CncBackend,
    ch: u16,
    field: Field,
    data: &[u8],
) -> Result<(), AdsResult> {
    if data.len() > 4 {
        return Err(AdsResult::INVALID_SIZE);
    }
    unit(match field {
        Field::Hold => backend.command(ch, Op::Hold),
        Field::Resume => backend.command(ch, Op::Resume),
        _ => backend.command(ch, Op::Reset),
    })
}

/// Every COM object in the description table answers at its address with its size.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::ads::testing;

    #[test]
    fn every_listed_readable_object_reads_its_size() {
        let t = testing::channels(1);
        let b = &t.backend;
        let list = objects(b.as_ref(), 0).unwrap();
        let mut names: Vec<_> = list.iter().map(|o| o.name.clone()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), list.len(), "names unique");
        for o in &list {
            let r = read(b.as_ref(), o.group, o.offset, o.size);
            if o.access.readable() {
                assert_eq!(r.map(|v| v.len() as u32), Ok(o.size), "{}", o.name);
            } else {
                assert_eq!(r, Err(AdsResult::ACCESS_DENIED), "{}", o.name);
            }
        }
    }

    #[test]
    fn twinsharp_platform_axis_form_and_index_groups() {
        let t = testing::channels(1);
        let b = &t.backend;
        let a = read(b.as_ref(), 0x120200, 0x1000F, 2).unwrap();
        let c = read(b.as_ref(), 0x120201, 0x0F, 2).unwrap();
        assert_eq!(a, c);
        assert_eq!(a, 1u16.to_le_bytes());
        assert_eq!(
            read(b.as_ref(), 0x20101, 0x0D, 4),
            read(b.as_ref(), 0x120101, 0x0D, 4)
        );
        assert_eq!(
            read(b.as_ref(), 0x120101, 0x7777, 4),
            Err(AdsResult::INVALID_OFFSET)
        );
        assert_eq!(
            read(b.as_ref(), 0x120102, 0x0D, 4),
            Err(AdsResult::INVALID_GROUP)
        );
        assert_eq!(
            read(b.as_ref(), 0x120101, 0x90, 1208),
            Err(AdsResult::ACCESS_DENIED)
        );
    }
}
