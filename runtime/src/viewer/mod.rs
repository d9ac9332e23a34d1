//! What a viewer is made of besides its window: the settings its panel edits (and the
//! `hprt render` command line that reproduces them), an orbiting camera, and the scripts that
//! drive it without a person. The program's window and a browser page share them.

mod orbit;
pub mod script;
mod settings;

pub use orbit::Orbit;
pub use settings::{SettingError, ViewSettings, shell_quote};
