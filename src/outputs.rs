//! What a command writes: never over what it reads (an output that is, or links to, one of its
//! inputs is refused before anything runs), and never two outputs at one file.

use anyhow::Context;
use foundation::infra::atomic_file::{AtomicOutput, commit_all};
use std::path::{Path, PathBuf};

/// One output of a command: the option that names it and its path.
pub type Output<'a> = (&'a str, Option<&'a Path>);

/// Refuses `outputs` that name the same file, or that are (or link to) any of `inputs`.
pub fn check_outputs(inputs: &[&Path], outputs: &[Output]) -> anyhow::Result<()> {
    let given: Vec<(&str, &Path)> = outputs
        .iter()
        .filter_map(|(option, path)| path.map(|p| (*option, p)))
        .collect();
    for (i, (a, pa)) in given.iter().enumerate() {
        for (b, pb) in &given[i + 1..] {
            if same_file(pa, pb) {
                anyhow::bail!(
                    "{a} and {b} name the same file {}: give each output its own path",
                    pb.display()
                );
            }
        }
    }
    for (option, output) in &given {
        if let Some(input) = inputs.iter().find(|input| same_file(output, input)) {
            anyhow::bail!(
                "{option} {} is {}, which this command reads: writing it would destroy the \
                 input; give the output another path",
                output.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Opens every given output (in order) before the work that fills them, so an unwritable one
/// fails first; [`write_outputs`] then writes them all together, or none.
pub fn open_outputs(outputs: &[Output]) -> anyhow::Result<Vec<AtomicOutput>> {
    outputs
        .iter()
        .filter_map(|(_, path)| *path)
        .map(|path| {
            AtomicOutput::create(path).with_context(|| format!("cannot write {}", path.display()))
        })
        .collect()
}

/// Writes `bytes` into the outputs [`open_outputs`] opened, in the same order, all or none.
pub fn write_outputs(files: Vec<AtomicOutput>, bytes: Vec<Vec<u8>>) -> anyhow::Result<()> {
    commit_all(files.into_iter().zip(bytes).collect()).context("cannot write the outputs")
}

/// Refuses a folder output that would write over an input: `files` are the files the command
/// writes into it.
pub fn check_folder_output(
    inputs: &[&Path],
    option: &str,
    folder: &Path,
    files: &[PathBuf],
) -> anyhow::Result<()> {
    for file in files {
        if let Some(input) = inputs.iter().find(|input| same_file(file, input)) {
            anyhow::bail!(
                "{option} {}: the command would write {} over {}, which this command reads; give the \
                 output another folder",
                folder.display(),
                file.display(),
                input.display()
            );
        }
    }
    Ok(())
}

pub use report::output::{check_folder_spares_inputs, scene_inputs};

/// Whether two paths name the same file: the same inode when both exist (links included),
/// else the same name in the same folder.
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        return ma.dev() == mb.dev() && ma.ino() == mb.ino();
    }
    let key = |p: &Path| {
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_owned());
        (dir, p.file_name().map(|n| n.to_owned()))
    };
    key(a) == key(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_over_inputs_are_refused_through_links_too() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("map.exr");
        std::fs::write(&input, b"x").unwrap();
        let link = dir.path().join("link.exr");
        std::os::unix::fs::symlink(&input, &link).unwrap();
        let other = dir.path().join("out.exr");
        assert!(check_outputs(&[&input], &[("-o", Some(&other))]).is_ok());
        for output in [&input, &link] {
            let e = check_outputs(&[&input], &[("-o", Some(output))]).unwrap_err();
            assert!(e.to_string().contains("which this command reads"), "{e}");
        }
        let e = check_outputs(&[], &[("-o", Some(&other)), ("--png", Some(&other))]).unwrap_err();
        assert!(e.to_string().contains("name the same file"), "{e}");
        let e = check_folder_spares_inputs(&[&input], "-o", dir.path()).unwrap_err();
        assert!(e.to_string().contains("holds"), "{e}");
    }
}
