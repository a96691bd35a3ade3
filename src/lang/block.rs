//! One NC block as the parser produces it and the decoder interprets it (TF5200 programming manual; README, "NC language").
//!
//! The parser is pure: one line in, one `Block` out. Nothing here knows about channels,
//! frames or files; the decoder gives these types their meaning. Columns are 1-based
//! character columns into the line, kept so that errors found later (an unknown label,
//! an undefined parameter) can still point at the right place.

use crate::vocab::flush::FlushKind;

/// A parsed NC line.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Block skip level: `/` is level 1, `/1`…`/10` as written. `None` = never skipped.
    pub skip_level: Option<u8>,
    /// The block number `N<n>` if present.
    pub n: Option<u32>,
    /// A jump target defined on this line: `N40:` or `[LABEL_1]`. The parser sets
    /// `Label::Number(k)` only together with `n == Some(k)`; printing writes `Nk:` for it.
    pub label: Option<Label>,
    pub body: Body,
}

impl Block {
    /// Most items a kept list may hold room for: a longer block's list (a 4000-character
    /// line of single letters holds about 2000) is freed rather than kept for the next line.
    const KEPT_ITEMS: usize = 64;

    /// This block's item list, taken out and emptied, for the next `parse_block_reusing`;
    /// `None` for a block of another kind, or one whose list grew past
    /// [`Self::KEPT_ITEMS`].
    pub fn take_items(&mut self) -> Option<Vec<Item>> {
        match &mut self.body {
            Body::Items(items) if items.capacity() <= Self::KEPT_ITEMS => {
                let mut items = std::mem::take(items);
                items.clear();
                Some(items)
            }
            _ => None,
        }
    }
}

/// A jump target: `N40:` defines `Label::Number(40)`, `[LOOP_1]` defines `Label::Name`.
/// Names are stored upper-case: labels are case-insensitive. Ordered, so label tables can be
/// B-trees (which never rehash a whole table in one tick).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Label {
    Number(u32),
    Name(String),
}

/// What the block does. `#` commands, `$` statements, calls and program heads stand alone
/// in their block (only `/`, `N` and a label may precede them).
///
/// Every kind but the ordinary block is boxed: a kept program holds a `Block` per line, most
/// of them ordinary, and the unboxed `Call` and `Control` made every block 104 bytes where
/// it is now 64.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// An ordinary block: words and assignments in written order. Empty for a blank or
    /// comment-only line.
    Items(Vec<Item>),
    /// A `$` control statement.
    Control(Box<Control>),
    /// A `#` command.
    Command(Box<Command>),
    /// `L file`, `LL name`, `L CYCLE [...]`.
    Call(Box<Call>),
    /// `%name` (main program head) or `%L name` (local subroutine head).
    ProgramHead(Box<ProgramHead>),
}

/// A program head: `%name` or `%L name`. A blank may stand between `%` and the name
/// (`% 100`); text after the name up to a comment is the program's `title`
/// (`% TestProgram for streaming mode`), empty when there is none.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramHead {
    pub name: String,
    /// `%L`: a local subroutine's head.
    pub local: bool,
    pub title: String,
}

/// One element of an ordinary block.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    Word(Word),
    /// `V.L.X=[..]`, `P[P1+5]=3`, `P1[2]=4`: an assignment to any variable but a plain
    /// `P<n>` ([`Item::AssignP`]). The target is boxed to keep `Item` at 48 bytes: plain word
    /// blocks are the hot path and their item lists are kept by the thousand.
    ///
    /// `op` is the operator of a combined assignment, `P2/=P1` (TF5200 diagnosis ID 20574
    /// names "the combined assignment operator /="): `+=`, `-=`, `*=` or `/=`; the new value
    /// is the target's old one with `value` by `op`. `None` for a plain `=`.
    Assign {
        target: Box<VarRef>,
        value: Expr,
        col: u32,
        op: Option<BinOp>,
    },
    /// `P1=10`: an assignment to `P<n>` with a constant number and no indices, the commonest
    /// of a streamed program, its target held inline so that a block of them takes no
    /// allocation besides its item list. `value`, `col` and `op` as for [`Item::Assign`].
    /// [`Item::assign`] makes this of every such target, so one assignment has one form.
    AssignP {
        number: u32,
        value: Expr,
        col: u32,
        op: Option<BinOp>,
    },
    /// A G function with a value: `G133=50`, `G134=50` (ramp time weighting in percent), and
    /// the dwell `G04 2.5` / `G04=2.5` / `G04 P1` (seconds). `G134 50` and `G134=50` both
    /// parse to this item. `col` is the G's column.
    GValue {
        g: u32,
        value: Value,
        col: u32,
    },
    /// An M or H function with a value for the PLC side: `M200=1200`, `H20=[P1*2]`
    /// (`letter` b'M' or b'H', `number` 0..=65535). `col` is the letter's column.
    FunctionValue {
        letter: u8,
        number: u32,
        value: Value,
        col: u32,
    },
    /// An axis named by more than its letter, `X1=10`, `Z_ACHSE = P1` (TF5200 programming
    /// manual, "Axis commands": such a name takes `=` before its value). Boxed: rare, and
    /// `Item` keeps its size. `col` is the name's column.
    NamedAxis(Box<NamedAxis>),
    /// An implicit subroutine call with transfer parameters, `G805[-27.12, 28.955, , 2.87]`
    /// (TF5200 programming manual, "Implicit subroutine calls (G80–G89/G800..)"): value k
    /// is `@P<k+1>` in the subroutine, a gap (`, ,`) is `None` (trailing gaps are dropped).
    /// `G800` without a bracket is an ordinary G word. `col` is the G's column. Boxed, so
    /// the variant leaves the enum's layout, and the drop of every plain word, as it was.
    GCall(Box<GCall>),
    /// `X[M54=P1]`, `S[REV 1000 M03 M63=-789]`: the technology functions of one axis or of
    /// the spindle (TF5200 programming manual, "Programming in spindle-specific syntax").
    /// Boxed, as [`Item::GCall`].
    Functions(Box<Functions>),
}

impl Item {
    /// The assignment of `value` to `target`: [`Item::AssignP`] for `P<n>` without indices,
    /// [`Item::Assign`] for any other target.
    pub fn assign(target: VarRef, value: Expr, col: u32, op: Option<BinOp>) -> Item {
        match target {
            VarRef::P {
                number: Index::Const(number),
                indices,
            } if indices.is_empty() => Item::AssignP {
                number,
                value,
                col,
                op,
            },
            target => Item::Assign {
                target: Box::new(target),
                value,
                col,
                op,
            },
        }
    }
}

/// The functions in an axis's or the spindle's brackets ([`Item::Functions`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Functions {
    /// The axis letter, or `S` for the spindle.
    pub owner: u8,
    /// M and H words (`Item::Word`, `Item::FunctionValue`) and, for the spindle, its speed
    /// `REV` as an S word, in written order.
    pub items: Vec<Item>,
    /// The owner's column.
    pub col: u32,
}

/// An axis named by more than its letter with its value ([`Item::NamedAxis`]).
#[derive(Debug, Clone, PartialEq)]
pub struct NamedAxis {
    pub name: AxisName,
    pub value: Value,
    pub col: u32,
}

/// Most characters of an axis name (P-CHAN-00006 `bezeichnung`: "maximum 16 characters").
pub(crate) const AXIS_NAME_MAX: usize = 16;

/// An axis name: a letter X Y Z A B C, then letters, digits and `_` (`X1`, `A1`, `Z_ACHSE`),
/// at most [`AXIS_NAME_MAX`] characters, upper-case. Fixed size, no allocation: the decoder
/// compares it with the channel's table, resolved once at set-up.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct AxisName {
    bytes: [u8; AXIS_NAME_MAX],
    len: u8,
}

impl AxisName {
    /// `name` as an axis name, or `None` if it is not one ncchannel can drive.
    pub fn new(name: &str) -> Option<Self> {
        let b = name.as_bytes();
        let first = b.first()?.to_ascii_uppercase();
        if b.len() > AXIS_NAME_MAX
            || !b"XYZABCUVW".contains(&first)
            || !b[1..]
                .iter()
                .all(|c| c.is_ascii_alphanumeric() || *c == b'_')
        {
            return None;
        }
        let mut bytes = [0u8; AXIS_NAME_MAX];
        for (d, s) in bytes.iter_mut().zip(b) {
            *d = s.to_ascii_uppercase();
        }
        Some(AxisName {
            bytes,
            len: b.len() as u8,
        })
    }

    /// The axis letter the name starts with: for X Y Z A B C the interpolator slot the axis
    /// takes (`params::runtime::channel_slots`).
    pub fn letter(&self) -> u8 {
        self.bytes[0]
    }

    /// The name is its letter alone (`X`, not `X1`). Asked for every axis word a block
    /// programs, so it reads the length rather than building the text.
    pub(crate) fn is_letter(&self) -> bool {
        self.len == 1
    }

    pub fn as_str(&self) -> &str {
        // Built from ASCII only.
        std::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

impl std::fmt::Display for AxisName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::fmt::Debug for AxisName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "AxisName({})", self.as_str())
    }
}

/// An implicit subroutine call's G number, transfer parameters and column ([`Item::GCall`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GCall {
    pub g: u32,
    pub args: Vec<Option<Expr>>,
    pub col: u32,
}

/// An address letter with its value: `G01`, `X12.5`, `F[P1*2]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Word {
    /// Upper-case ASCII address letter (G M H F S T D X Y Z A B C I J K R E).
    pub letter: u8,
    pub value: Value,
    /// Column of the letter.
    pub col: u32,
}

/// A word's value: a literal (the common case, no allocation) or an expression.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Num(f64),
    Expr(Expr),
}

/// A reference to a parameter or variable, indices not yet evaluated.
#[derive(Debug, Clone, PartialEq)]
pub enum VarRef {
    /// `P<n>` or indirect `P[expr]`, with optional array indices `P1[2]`, `P1[i][j]`.
    P { number: Index, indices: Vec<Expr> },
    /// `V.P.name`, `V.L.name`, `V.S.name`, `V.E.name`, optional array indices. Name upper-case.
    V {
        scope: VScope,
        name: String,
        indices: Vec<Expr>,
    },
    /// `@P<n>`: a cycle parameter, visible inside a cycle called by `L CYCLE [... @Pn=..]`.
    CycleParam(u32),
    /// `V.A.ABS.X` / `V.A.ABS[0]`: the axis' absolute coordinate at the end of the previous
    /// block, in the active coordinate system (TF5200 programming manual, "Axis-specific
    /// variables (V.A.)"). Read-only.
    AxisAbs(AxisSel),
    /// `V.G.WZ_AKT.R` (the active tool's radius; `None`) or `V.G.WZ[j].R` (tool data set
    /// j's), mm, from the tool list (TF5200 programming manual, "Global variables (V.G.)").
    /// Read-only.
    ToolRadius(Option<Box<Expr>>),
    /// `V.G.WZ_AKT.<field>` (`tool` `None`: the active tool) or `V.G.WZ[j].<field>`: the tool
    /// list's length, validity flag or axis offset (TF5200 "Access to tool data in the NC
    /// program (V.G.WZ..)"). Read-only.
    ToolData {
        tool: Option<Box<Expr>>,
        field: ToolField,
    },
    /// `V.G.NP[i].V.<axis>` / `V.G.NP[i].V[j]`: zero-offset group i's offset on an axis, mm
    /// (group 0 = G53, none; 1 … 6 = G54 … G59; TF5200 programming manual, "Zero offsets").
    /// Read-only.
    ZeroOffset { group: Box<Expr>, axis: AxisSel },
    /// `V.G.M_FCT[n].SYNCH` / `V.G.H_FCT[n].SYNCH`: the synchronisation type of M or H
    /// function n, as the kernel's value (TF5200 "Parameterising the synchronisation
    /// methods": the program may change what `m_synch` / `h_synch` configured).
    FunctionSync { h: bool, number: Box<Expr> },
}

/// A field of a tool data set besides the radius (`V.G.WZ_AKT.L`, `.OK`, `.V.X`).
#[derive(Debug, Clone, PartialEq)]
pub enum ToolField {
    /// `L`: the length, mm.
    Length,
    /// `OK`: the validity flag, 1 = valid.
    Valid,
    /// `V.<axis>` / `V[i]`: the axis offset, mm.
    AxisOffset(AxisSel),
}

/// The axis of a `V.A.` variable: by name (`.X`) or by index in the channel's axis list.
#[derive(Debug, Clone, PartialEq)]
pub enum AxisSel {
    /// Upper-case axis letter.
    Name(u8),
    Index(Box<Expr>),
}

/// The number of a P parameter: written out, or computed (`P[P1+5]`).
#[derive(Debug, Clone, PartialEq)]
pub enum Index {
    Const(u32),
    Expr(Box<Expr>),
}

/// Scope of a `V.` variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum VScope {
    /// `V.P.` program-global, cleared at program start.
    Program,
    /// `V.L.` local to its program level and its callees.
    Local,
    /// `V.S.` self-retaining: survives reset.
    SelfRetaining,
    /// `V.E.` external: set from outside through the channel API / ADS.
    External,
}

/// An expression tree. Grouping `[ ]` leaves no node of its own.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    Num(f64),
    Var(Box<VarRef>),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    Func(Func, Vec<Expr>),
    /// `EXIST[v]`, `IS_NUMBER[v]`, `IS_STRING[v]`: a question about a variable rather than
    /// its value (1 or 0), so an undefined `v` is no error here.
    Test(VarTest, Box<VarRef>),
    /// A quoted string `"text"` (at most [`MAX_STRING`] characters, no quote inside).
    Str(Box<str>),
    /// A string function (TF5200 programming manual, "Operations for character strings"):
    /// `LEN["abc"]`, `MID[V.L.S, 3, 5]`.
    StrFunc(StrFunc, Vec<Expr>),
}

/// Most characters a string value holds: a `STRING[n]` declares n of 1 to 126 (TF5200
/// programming manual, "Variables"; ISG's editor grammar), and no string value is longer.
pub(crate) const MAX_STRING: usize = 126;

/// The string functions of TF5200 "Operations for character strings" ncchannel evaluates.
/// Positions count characters from 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrFunc {
    /// `LEN[str]`: the number of characters.
    Len,
    /// `LEFT[str, anz]`: the first anz characters.
    Left,
    /// `RIGHT[str, anz]`: the last anz characters.
    Right,
    /// `MID[str, anz, pos]`: anz characters from position pos.
    Mid,
    /// `FIND[str1, str2]`: the position of str2's first occurrence in str1 (case-sensitive),
    /// 0 when there is none.
    Find,
    /// `ORD[str]`, `ORD[str, pos]`: the character value at pos (1 when not given).
    Ord,
    /// `DELETE[str, anz, pos]`: str without the anz characters from position pos (TF5200
    /// diagnosis 21545's example).
    Delete,
}

/// What `Expr::Test` asks about its variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarTest {
    /// `EXIST[v]`: `v` has a value, a number or a string.
    Exist,
    /// `IS_NUMBER[v]`: `v` holds a number.
    IsNumber,
    /// `IS_STRING[v]`: `v` holds a string (a `STRING[n]` variable, a cycle parameter
    /// `@P1="text"`).
    IsString,
}

impl VarTest {
    /// The function's name as written in NC text.
    pub fn name(self) -> &'static str {
        match self {
            VarTest::Exist => "EXIST",
            VarTest::IsNumber => "IS_NUMBER",
            VarTest::IsString => "IS_STRING",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnOp {
    Neg,
    /// Logical `NOT`.
    Not,
    /// Bitwise `INV`.
    Inv,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Mod,
    Eq,
    Ne,
    Lt,
    Gt,
    Le,
    Ge,
    And,
    Or,
    Xor,
    BitAnd,
    BitOr,
    BitXor,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    Abs,
    Sqr,
    Sqrt,
    Exp,
    Ln,
    Log,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    Int,
    Fract,
    Round,
    Floor,
    Ceil,
}

/// A `$` statement.
#[derive(Debug, Clone, PartialEq)]
pub enum Control {
    If(Expr),
    /// `$IF <cond> $GOTO <target>`: the one statement that may follow another in a block.
    IfGoto(Expr, GotoTarget),
    ElseIf(Expr),
    Else,
    EndIf,
    Switch(Expr),
    Case(Expr),
    Default,
    Break,
    EndSwitch,
    /// `$FOR P1 = start, end, step` (step optional, default 1). Boxed parts keep `Block`
    /// small (104 bytes instead of 192); `&Box<Expr>` derefs to `&Expr` where passed.
    For {
        var: Box<VarRef>,
        start: Box<Expr>,
        end: Box<Expr>,
        step: Option<Box<Expr>>,
    },
    EndFor,
    While(Expr),
    EndWhile,
    Do,
    EndDo(Expr),
    Repeat,
    Until(Expr),
    Continue,
    Goto(GotoTarget),
}

/// Where a `$GOTO` jumps: `N40` or `[LABEL]` (name upper-case).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum GotoTarget {
    Number(u32),
    Name(String),
}

/// A `#` command.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    Flush(FlushKind),
    /// `#EXPL SYN`: the explicit synchronisation point of MVS_SLP technology functions
    /// (TF5200 "Example of MVS_SLP").
    ExplicitSync,
    /// `#CACHE LOAD [FILE=name]`.
    CacheLoad {
        file: String,
    },
    /// `#CACHE CLEAR [FILE=name]`.
    CacheClear {
        file: String,
    },
    /// `#CACHE CLEAR ALL`.
    CacheClearAll,
    CommentBegin,
    CommentEnd,
    /// `#SPLINE ON`, `#SPLINE OFF`, `#SPLINE TYPE AKIMA|BSPLINE`.
    Spline(SplineCommand),
    /// `#HSC ON [...]` / `#HSC OFF`; the bracket text is kept verbatim.
    Hsc {
        on: bool,
        options: String,
    },
    /// `#CONTOUR MODE [...]`; the bracket text kept verbatim.
    ContourMode {
        options: String,
    },
    /// `#CONTOUR MODE ON [...]` (parameters as `ContourMode`, then contouring on as G261) and
    /// `#CONTOUR MODE OFF` (as G260) (TF5200 programming manual, "Activating contouring modes
    /// in the NC program").
    ContourSwitch {
        on: bool,
        options: String,
    },
    /// `#VAR` … `#ENDVAR`: declarations of V.P./V.L./V.S. variables in between.
    Var,
    EndVar,
    /// `#MSG ["text", values…]`, `#MSG SAVE …`, `#MSG INFO …`: an operator message
    /// (`super::msg`). Boxed: messages are rare and `Block` stays small.
    Msg(Box<Message>),
    /// `#TIME <seconds>`: a dwell (TF5200 "Dwell time").
    Time(Value),
    /// `#FILENAME [MSG=V.E.NAME]`: the report file of `#MSG SAVE` named by a string variable
    /// (TF5200 programming manual, "Definition of file names"; ISG's teach programs take it
    /// from a V.E. string the HMI sets). ncchannel writes no report file, but the variable
    /// is read, so an undeclared or numeric one is refused as the kernel would.
    MsgFileName(Box<VarRef>),
    /// `#TRAFO`, `#KIN`, `#CS` in a form that leaves the path as it is (`super::transform`).
    /// Boxed: rare, and `Block` stays small.
    Transform(Box<Transform>),
    /// A `#` command of ISG's list that ncchannel accepts without effect
    /// (`super::dialect`); the whole command text after `#` is kept verbatim.
    Inert {
        text: String,
    },
}

/// A transformation command in a neutral form (`super::transform`); `text` is the command
/// after `#`, verbatim.
#[derive(Debug, Clone, PartialEq)]
pub enum Transform {
    /// `#TRAFO OFF`, `#TRAFO [NONE]`, `#KIN ID [NONE]`, `#CS OFF`, `#CS OFF ALL`.
    Off { text: String },
    /// `#CS DEF [id] [v1,v2,v3,φ1,φ2,φ3]`, or `#CS ON …` (`select`) with the values.
    CsDefine {
        text: String,
        id: Option<Expr>,
        values: Vec<Expr>,
        select: bool,
    },
    /// `#CS ON [id]`, `#CS ON`: a CS defined before.
    CsSelect { text: String, id: Option<Expr> },
}

impl Transform {
    /// The command after `#`, as written.
    pub fn text(&self) -> &str {
        match self {
            Transform::Off { text }
            | Transform::CsDefine { text, .. }
            | Transform::CsSelect { text, .. } => text,
        }
    }
}

/// An operator message (TF5200 programming manual, "Messages from the NC program").
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// The keywords between `#MSG` and the bracket, upper-case, as written: `SAVE EXCLUSIVE`,
    /// `INFO`, `SYN HMI`.
    pub options: Vec<&'static str>,
    /// The format text without its quotes, or the bracket text verbatim when it is not one
    /// quoted string (then `quoted` is false and nothing is formatted).
    pub text: String,
    pub quoted: bool,
    /// The values for the text's format elements, as many as it has.
    pub args: Vec<Expr>,
}

impl Message {
    /// `#MSG SAVE …`: the kernel writes it to its report file as well.
    pub fn save(&self) -> bool {
        self.options.first() == Some(&"SAVE")
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SplineCommand {
    On,
    Off,
    TypeAkima,
    TypeBspline,
}

/// A subroutine or cycle call.
#[derive(Debug, Clone, PartialEq)]
pub enum Call {
    /// `L file.nc`: global subroutine, found through the program search paths.
    Global { file: String },
    /// `LL name`: local subroutine defined by `%L name` in the same file.
    Local { name: String },
    /// `L CYCLE [NAME=file.cyc @P1=0 @P2="text"]` (a cycle file), or with `local`
    /// `LL CYCLE [NAME=sub @P1=0]` (a `%L sub` section of the calling file).
    Cycle {
        name: String,
        local: bool,
        params: Vec<(u32, CycleArg)>,
    },
}

/// The value of a cycle parameter `@P<n>=…`: an expression, evaluated at the call, or a
/// quoted string (`@P1="String1"`), carried as written (docs/nc-language.md, "Constructs of
/// real programs").
#[derive(Debug, Clone, PartialEq)]
pub enum CycleArg {
    Expr(Expr),
    Str(String),
}

/// One declaration inside `#VAR` … `#ENDVAR`: `V.L.COUNT = 5`, `V.P.TABLE[10]`,
/// `V.L.N : UNS32 = 10`, `V.P.ROW[3] = [10, 11, 12]`.
#[derive(Debug, Clone, PartialEq)]
pub struct VarDecl {
    pub scope: VScope,
    /// Upper-case name.
    pub name: String,
    /// Array dimensions as declared (`[10]` → `[10]`); empty for a scalar.
    pub dims: Vec<u32>,
    /// The type named after `:`, if one is (`V.L.N : UNS32`).
    pub ty: Option<VarType>,
    /// The value every element starts with (`= 5`); none for a list or a string.
    pub init: Option<Expr>,
    /// The start value of a `STRING[n]` variable (`= "GRUNDPLATTE"`), without its quotes.
    pub text: Option<String>,
    /// An array initialiser `= [10, 11, 12]`: the first elements in row-major order (the
    /// rest stay 0). Empty when there is none.
    pub values: Vec<Expr>,
}

/// The data types a declaration may name (TF5200 programming manual, "Variables": the
/// elementary types of V.E. variables, as ISG's editor grammar lists them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarType {
    Boolean,
    Sgn08,
    Uns08,
    Sgn16,
    Uns16,
    Sgn32,
    Uns32,
    /// `REAL` or `REAL64`.
    Real,
    /// `STRING[n]`, n characters at most (1 to [`MAX_STRING`]): the variable holds a
    /// string (docs/nc-language.md, "Strings").
    String(u8),
}

impl VarType {
    /// The numeric types, each named by [`VarType::name`].
    const NUMERIC: [VarType; 8] = [
        VarType::Boolean,
        VarType::Sgn08,
        VarType::Uns08,
        VarType::Sgn16,
        VarType::Uns16,
        VarType::Sgn32,
        VarType::Uns32,
        VarType::Real,
    ];

    /// The numeric type named `upper` (upper case; `REAL` is `REAL64`).
    pub fn numeric(upper: &str) -> Option<VarType> {
        if upper == "REAL" {
            return Some(VarType::Real);
        }
        Self::NUMERIC.into_iter().find(|t| t.name() == upper)
    }

    /// The values an integer type holds (BOOLEAN 0 … 1); `None` for REAL64 and strings.
    pub fn range(self) -> Option<(f64, f64)> {
        Some(match self {
            VarType::Boolean => (0.0, 1.0),
            VarType::Sgn08 => (f64::from(i8::MIN), f64::from(i8::MAX)),
            VarType::Uns08 => (0.0, f64::from(u8::MAX)),
            VarType::Sgn16 => (f64::from(i16::MIN), f64::from(i16::MAX)),
            VarType::Uns16 => (0.0, f64::from(u16::MAX)),
            VarType::Sgn32 => (f64::from(i32::MIN), f64::from(i32::MAX)),
            VarType::Uns32 => (0.0, f64::from(u32::MAX)),
            VarType::Real | VarType::String(_) => return None,
        })
    }

    /// The type's name as written in a declaration (`REAL` as `REAL64`).
    pub fn name(self) -> &'static str {
        match self {
            VarType::Boolean => "BOOLEAN",
            VarType::Sgn08 => "SGN08",
            VarType::Uns08 => "UNS08",
            VarType::Sgn16 => "SGN16",
            VarType::Uns16 => "UNS16",
            VarType::Sgn32 => "SGN32",
            VarType::Uns32 => "UNS32",
            VarType::Real => "REAL64",
            VarType::String(_) => "STRING",
        }
    }
}

#[cfg(all(test, target_pointer_width = "64"))]
mod tests {
    use super::{Block, Item};

    /// A kept program holds one `Block` a line and its items: a variant that grows either
    /// makes every program larger (the boxed variants above are boxed for this).
    #[test]
    fn blocks_and_items_keep_their_size() {
        assert_eq!(std::mem::size_of::<Block>(), 64);
        assert_eq!(std::mem::size_of::<Item>(), 48);
    }
}
