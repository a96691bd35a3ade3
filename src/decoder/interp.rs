//! The interpreter: what a block does once read — modal state, variables, the block counter,
//! calls and cycles, block search and the block's words — and the queueing of the blocks
//! that take effect. Its methods are spread over the files of `interp/` (`words.rs`,
//! `calls.rs`, `cycles.rs`, `search.rs`, `axis_vars.rs`), which see its fields; the frame
//! stack they work on is the [`Reader`]'s, passed in.

mod axis_vars;
mod block_words;
mod calls;
mod cycles;
mod expr;
mod implicit;
mod search;
mod techno;
mod transform;
mod words;

use super::error::{var_error, Res};
use super::flow::Env;
use super::io::DecoderIo;
use super::line::BlockAt;
use super::modal::{Modal, ZeroOffsets};
use super::note::Note;
use super::reader::Reader;
use super::search_target::{Search, SearchTarget};
use super::settings::DecoderSettings;
use super::vars::{VarSlot, VarStore};
use crate::lang::block::{Expr, VarRef};
use crate::params::tools::ToolTable;
use crate::queue::{Action, BlockInfo, QueuedBlock};
use crate::source::loader::Loader;
use crate::vocab::axis::{Position, MAX_AXES};
use block_words::Words;
use implicit::ImplicitState;
use techno::TechnoState;

/// Modal state, variables and the running program's calls.
#[derive(Debug)]
pub(super) struct Interpreter {
    settings: DecoderSettings,
    /// Bit i: the configured axis in slot i has a name longer than its letter (`X1`), so the
    /// letter alone names no axis. Read for every axis word; built once from the settings.
    renamed_slots: u8,
    vars: VarStore,
    modal: Modal,
    /// The tool list's data sets by D number, mm (`V.G.WZ[j].*`, G41/G42, length
    /// compensation).
    tools: ToolTable,
    /// `einrechnen_mit_t` (P-CHAN-00014): a T word also selects the D data set of its number.
    t_selects_d: bool,
    /// Zero-offset groups G54 … G59 by axis, mm: the list's values at start-up, then what
    /// programs write to `V.G.NP[i]` (kept across resets, as the kernel's table is).
    zero_offsets: ZeroOffsets,
    /// ISG block counter of the current program.
    counter: u64,
    search: Option<Search>,
    /// Bit n set: blocks with `/n` are skipped (`/` is `/1`).
    skip_mask: u16,
    /// Blocks queued that take effect (`DecoderStats::blocks`).
    blocks: u64,
    /// The main program's end (M02/M30) has been decoded since the decoder last asked.
    ended: bool,
    /// The word collection of the block being executed, kept between blocks.
    words: Option<Box<Words>>,
    /// The implicit subroutine calls' state in the running program.
    implicit: ImplicitState,
    /// M/H/S/T functions: the channel's table, sequence numbers, late synchronisations.
    techno: TechnoState,
}

impl Interpreter {
    pub(super) fn new(settings: DecoderSettings, loader: Loader) -> Self {
        // `X1` in slot X, or `W` in slot Z: the slot's letter alone names no axis.
        let renamed_slots = (0..MAX_AXES)
            .filter(|&i| {
                let n = &settings.axis_names[i];
                settings.axes[i]
                    && !(n.is_letter() && n.letter() == crate::vocab::axis::AXIS_LETTERS[i])
            })
            .fold(0u8, |m, i| m | 1 << i);
        let techno = TechnoState::new(settings.techno.clone(), settings.implicit.at_m6.is_some());
        let mut vars = VarStore::new(loader);
        if let Some(t) = &settings.ext_vars {
            // The list reader refuses a table larger than the V.E. class budget
            // (params::ext_vars, `MAX_TABLE_BYTES`), so this cannot run out of memory.
            let _ = vars.declare_externals(t.clone());
        }
        Interpreter {
            techno,
            zero_offsets: settings.zero_offsets,
            settings,
            renamed_slots,
            vars,
            modal: Modal::defaults([0.0; MAX_AXES]),
            tools: Vec::new(),
            t_selects_d: false,
            counter: 0,
            search: None,
            skip_mask: 0,
            blocks: 0,
            ended: false,
            words: None,
            implicit: ImplicitState::default(),
        }
    }

    /// A main program starts: channel defaults, the block counter from 0, the start
    /// subroutine to call, a block search when asked for.
    pub(super) fn start(&mut self, machine_pos: Position, search: Option<SearchTarget>) {
        self.modal = Modal::defaults(machine_pos);
        self.vars.start_program();
        self.counter = 0;
        self.implicit = ImplicitState::at_start(&self.settings.implicit);
        self.search = search.map(|target| Search {
            target,
            from: machine_pos,
        });
    }

    /// Channel reset: parameters and modal state go; V.S. stays.
    pub(super) fn reset(&mut self, machine_pos: Position) {
        self.vars.reset();
        self.modal = Modal::defaults(machine_pos);
        self.counter = 0;
        self.search = None;
        self.implicit = ImplicitState::default();
        self.techno.reset();
    }

    pub(super) fn settings(&self) -> &DecoderSettings {
        &self.settings
    }
    pub(super) fn modal(&self) -> &Modal {
        &self.modal
    }
    /// Zero-offset groups G54 … G59 by axis, mm, as programs have left them.
    pub(super) fn zero_offsets(&self) -> &ZeroOffsets {
        &self.zero_offsets
    }
    pub(super) fn vars(&self) -> &VarStore {
        &self.vars
    }
    pub(super) fn vars_mut(&mut self) -> &mut VarStore {
        &mut self.vars
    }
    pub(super) fn counter(&self) -> u64 {
        self.counter
    }
    /// Blocks queued that take effect.
    pub(super) fn blocks(&self) -> u64 {
        self.blocks
    }
    pub(super) fn searching(&self) -> bool {
        self.search.is_some()
    }
    /// An error stopped decoding: no block search goes on.
    pub(super) fn end_search(&mut self) {
        self.search = None;
    }
    pub(super) fn set_skip_mask(&mut self, mask: u16) {
        self.skip_mask = mask;
    }
    /// Blocks with `/level` are skipped.
    pub(super) fn skips_level(&self, level: u8) -> bool {
        self.skip_mask & (1u16 << level.min(15)) != 0
    }
    /// The tool list's data sets by D number (mm), and whether T selects D as well
    /// (`einrechnen_mit_t`, P-CHAN-00014).
    pub(super) fn set_tools(&mut self, tools: ToolTable, t_selects_d: bool) {
        self.tools = tools;
        self.t_selects_d = t_selects_d;
    }

    /// A line is run: the ISG block counter counts it.
    pub(super) fn count_line(&mut self) {
        self.counter += 1;
    }

    /// A line that waits did nothing: its count is given back.
    pub(super) fn give_back_line(&mut self) {
        self.counter -= 1;
    }

    /// `true` once after the main program's end has been decoded.
    pub(super) fn take_ended(&mut self) -> bool {
        std::mem::take(&mut self.ended)
    }

    /// M30/M2: the program ends; in a stream the rest of the current segment goes.
    pub(super) fn end_program(&mut self, rd: &mut Reader, notes: &mut Vec<Note>) {
        rd.end_program(notes);
        self.ended = true;
    }

    pub(super) fn eval(&self, e: &Expr) -> Res<f64> {
        expr::eval(e, &expr::Env(self))
    }

    pub(super) fn resolve(&self, v: &VarRef) -> Res<VarSlot> {
        expr::resolve(v, &expr::Env(self))
    }

    pub(super) fn set_var(&mut self, k: VarSlot, v: f64) -> Res {
        self.vars.set(k, v).map_err(var_error)
    }

    /// [`Self::set_var`] of `P<number>` without indices.
    pub(super) fn set_p(&mut self, number: u32, v: f64) -> Res {
        self.vars.set_p(number, v).map_err(var_error)
    }

    /// A variable's value (`None`: not defined).
    pub(super) fn var(&self, k: &VarSlot) -> Option<f64> {
        self.vars.get(k)
    }

    /// What the queue and the event log say about the block of `text` at `meta` in the
    /// reader's running frame.
    pub(super) fn info(&self, rd: &Reader, at: BlockAt<'_>, io: &DecoderIo<'_>) -> BlockInfo {
        let top = rd.current();
        BlockInfo {
            prog: top.prog().clone(),
            line: at.meta.line,
            offset: at.meta.offset,
            counter: self.counter,
            n: at.block.n,
            text: io.want_text.then(|| at.text.into()),
            stream: top.is_stream(),
        }
    }

    /// Queue a block that takes effect. During block search nothing is queued: the block
    /// was evaluated, its state collected.
    pub(super) fn emit(
        &mut self,
        info: BlockInfo,
        action: Action,
        silent: bool,
        io: &mut DecoderIo<'_>,
    ) {
        if self.search.is_some() {
            return;
        }
        if !silent {
            self.blocks += 1;
        }
        io.queue.push(QueuedBlock {
            info,
            action,
            silent,
        });
    }
}

/// The skip machine's expressions and `$FOR` variable, as the running program sees them.
impl Env for Interpreter {
    fn eval(&self, e: &Expr) -> Res<f64> {
        Interpreter::eval(self, e)
    }
    fn resolve(&self, v: &VarRef) -> Res<VarSlot> {
        Interpreter::resolve(self, v)
    }
    fn var(&self, k: &VarSlot) -> Option<f64> {
        Interpreter::var(self, k)
    }
    fn set_var(&mut self, k: VarSlot, v: f64) -> Res {
        Interpreter::set_var(self, k, v)
    }
}
