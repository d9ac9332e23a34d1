//! Scripted input for a viewer (`hprt view --script FILE`): drives it without a person, for
//! the smoke test and for reproducible timings. One command per line, `#` starts a comment:
//!
//! ```text
//! wait 5                    # let 5 frames pass
//! wait-bake                 # until the bake the viewer started has finished
//! orbit 40 -10              # drag with the left button by (dx, dy) pixels
//! pan 20 0                  # drag with the right button
//! zoom 2                    # wheel notches (positive: closer)
//! reset                     # the scene's camera again
//! set rotation 30           # any setting of the panel, see `Setting`
//! screenshot scene.png      # the rendered image, tone-mapped
//! window-screenshot ui.png  # the whole window, panels included
//! command render.sh         # the equivalent `hprt render` command line
//! move 1 0 -0.5             # move the virtual objects by (dx, dy, dz) (re-baked; live in a
//!                           # room with probes)
//! place 1 0.4 -0.5          # a room's model: put its centre there (live)
//! turn 30                   # a room's model: turn it 30° about the vertical (live)
//! state state.json          # lights, timings and visible panels, as JSON
//! quit
//! ```

use std::path::{Path, PathBuf};

#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    Wait(u32),
    WaitBake,
    Orbit(f32, f32),
    Pan(f32, f32),
    Zoom(f32),
    Reset,
    Set(String, String),
    Screenshot(PathBuf),
    WindowScreenshot(PathBuf),
    SaveRenderLine(PathBuf),
    State(PathBuf),
    /// Move the virtual objects (not the proxies) by this offset.
    Move(glam::Vec3),
    /// Put the centre of a room's model here.
    Place(glam::Vec3),
    /// Turn a room's model by this many degrees about the vertical.
    Turn(f32),
    Quit,
}

/// What is wrong with a script's line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScriptProblem {
    ExpectedNumber,
    ExpectedPath,
    ExpectedSet,
    UnknownCommand,
}

impl ScriptProblem {
    fn describe(self) -> &'static str {
        match self {
            ScriptProblem::ExpectedNumber => "expected a number",
            ScriptProblem::ExpectedPath => "expected a path",
            ScriptProblem::ExpectedSet => "expected `set NAME VALUE`",
            ScriptProblem::UnknownCommand => "unknown command",
        }
    }
}

/// A script's line that cannot be run, with its file and number (from 1).
#[derive(Debug, thiserror::Error)]
#[error("{}: line {number}: {}: {line:?}", path.display(), problem.describe())]
pub struct ScriptError {
    pub path: PathBuf,
    pub number: usize,
    pub line: String,
    pub problem: ScriptProblem,
}

/// Parses a script; errors name the file and line.
pub fn parse(path: &Path, text: &str) -> Result<Vec<Command>, ScriptError> {
    let mut commands = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        let error = |problem| ScriptError {
            path: path.to_path_buf(),
            number: number + 1,
            line: line.to_owned(),
            problem,
        };
        let number_at = |i: usize| -> Result<f32, ScriptError> {
            words
                .get(i)
                .and_then(|w| w.parse::<f32>().ok())
                .ok_or_else(|| error(ScriptProblem::ExpectedNumber))
        };
        let path_at = |i: usize| -> Result<PathBuf, ScriptError> {
            words
                .get(i)
                .map(PathBuf::from)
                .ok_or_else(|| error(ScriptProblem::ExpectedPath))
        };
        let command = match words[0] {
            "wait" => Command::Wait(number_at(1)? as u32),
            "wait-bake" => Command::WaitBake,
            "orbit" => Command::Orbit(number_at(1)?, number_at(2)?),
            "pan" => Command::Pan(number_at(1)?, number_at(2)?),
            "zoom" => Command::Zoom(number_at(1)?),
            "reset" => Command::Reset,
            "set" if words.len() == 3 => Command::Set(words[1].to_owned(), words[2].to_owned()),
            "set" => return Err(error(ScriptProblem::ExpectedSet)),
            "screenshot" => Command::Screenshot(path_at(1)?),
            "window-screenshot" => Command::WindowScreenshot(path_at(1)?),
            "command" => Command::SaveRenderLine(path_at(1)?),
            "move" => Command::Move(glam::Vec3::new(number_at(1)?, number_at(2)?, number_at(3)?)),
            "turn" => Command::Turn(number_at(1)?),
            "place" => Command::Place(glam::Vec3::new(number_at(1)?, number_at(2)?, number_at(3)?)),
            "state" => Command::State(path_at(1)?),
            "quit" => Command::Quit,
            _ => return Err(error(ScriptProblem::UnknownCommand)),
        };
        commands.push(command);
    }
    Ok(commands)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_command_and_reports_bad_lines() {
        let text = "# smoke\nwait 3\norbit 10 -5\npan 1 2\nzoom -1.5\nreset\nset rotation 30\n\
                    screenshot a.png\nwindow-screenshot b.png\ncommand c.sh\nstate d.json\n\
                    place 1 0.5 -2\nturn -45\nquit\n";
        let commands = parse(Path::new("s.txt"), text).unwrap();
        assert_eq!(commands.len(), 13);
        assert_eq!(commands[11], Command::Turn(-45.0));
        assert_eq!(
            commands[10],
            Command::Place(glam::Vec3::new(1.0, 0.5, -2.0))
        );
        assert_eq!(commands[1], Command::Orbit(10.0, -5.0));
        assert_eq!(commands[5], Command::Set("rotation".into(), "30".into()));
        let err = parse(Path::new("s.txt"), "wait\n").unwrap_err().to_string();
        assert!(err.contains("s.txt: line 1"), "{err}");
        let unknown = parse(Path::new("s.txt"), "wait 1\nfly 1\n").unwrap_err();
        assert_eq!(
            (unknown.number, unknown.problem),
            (2, ScriptProblem::UnknownCommand)
        );
    }
}
