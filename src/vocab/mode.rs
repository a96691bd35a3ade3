//! Channel modes and states: the numbers of ISG's HLI (`HLI_IMCM_*`, docs/ads.md) and their
//! names, as the event log and error messages spell them (the variant in capitals).

use std::fmt;

use serde::Serialize;

/// Channel modes: the ISG HLI numbers (docs/ads.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Mode {
    Standby = 1,
    Automatic = 2,
    Mdi = 3,
    Manual = 4,
    /// Homing (ISG's reference mode).
    Reference = 5,
}

/// Channel states: the ISG HLI numbers (docs/ads.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum State {
    Deselected = 1,
    Selected = 2,
    Ready = 3,
    Active = 4,
    Hold = 5,
    Error = 6,
}

impl Mode {
    pub(crate) fn from_i32(v: i32) -> Option<Mode> {
        Some(match v {
            1 => Mode::Standby,
            2 => Mode::Automatic,
            3 => Mode::Mdi,
            4 => Mode::Manual,
            5 => Mode::Reference,
            _ => return None,
        })
    }
}

impl State {
    pub(crate) fn from_i32(v: i32) -> Option<State> {
        Some(match v {
            1 => State::Deselected,
            2 => State::Selected,
            3 => State::Ready,
            4 => State::Active,
            5 => State::Hold,
            6 => State::Error,
            _ => return None,
        })
    }
}

/// The name serde gives the variant (`rename_all = "UPPERCASE"`): one spelling for the event
/// log and the messages.
fn upper_name(debug: String, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    f.write_str(&debug.to_ascii_uppercase())
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        upper_name(format!("{self:?}"), f)
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        upper_name(format!("{self:?}"), f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_and_serde_spell_the_same_names() {
        for m in (1..=5).filter_map(Mode::from_i32) {
            let json = serde_json::to_string(&m).unwrap_or_default();
            assert_eq!(json, format!("\"{m}\""));
        }
        for s in (1..=6).filter_map(State::from_i32) {
            let json = serde_json::to_string(&s).unwrap_or_default();
            assert_eq!(json, format!("\"{s}\""));
        }
        assert_eq!(Mode::Mdi.to_string(), "MDI");
        assert_eq!(State::Hold.to_string(), "HOLD");
    }
}
