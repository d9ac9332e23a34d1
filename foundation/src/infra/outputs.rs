//! What a command writes: never over what it reads (an output that is, or links to, one of its
//! inputs is refused before anything runs), and never two outputs at one file.

use std::path::{Path, PathBuf};

/// One output of a command: the option that names it and its path.
pub type Output<'a> = (&'a str, Option<&'a Path>);

/// Why outputs were refused.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{first} and {second} name the same file {}: give each output its own path", path.display())]
    SameFile {
        first: String,
        second: String,
        path: PathBuf,
    },
    #[error(
        "{option} {} is {}, which this command reads: writing it would destroy the input; give \
         the output another path",
        output.display(),
        input.display()
    )]
    OverInput {
        option: String,
        output: PathBuf,
        input: PathBuf,
    },
    #[error(
        "{option} {}: the command would write {} over {}, which this command reads; give the \
         output another folder",
        folder.display(),
        file.display(),
        input.display()
    )]
    FolderOverInput {
        option: String,
        folder: PathBuf,
        file: PathBuf,
        input: PathBuf,
    },
}

/// Refuses `outputs` that name the same file, or that are (or link to) any of `inputs`.
pub fn check_outputs(inputs: &[&Path], outputs: &[Output]) -> Result<(), OutputError> {
    let given: Vec<(&str, &Path)> = (outputs.iter())
        .filter_map(|(option, path)| path.map(|p| (*option, p)))
        .collect();
    for (i, (a, pa)) in given.iter().enumerate() {
        if let Some((b, pb)) = given[i + 1..].iter().find(|(_, pb)| same_file(pa, pb)) {
            return Err(OutputError::SameFile {
                first: (*a).to_owned(),
                second: (*b).to_owned(),
                path: pb.to_path_buf(),
            });
        }
    }
    for (option, output) in &given {
        if let Some(input) = inputs.iter().find(|input| same_file(output, input)) {
            return Err(OutputError::OverInput {
                option: (*option).to_owned(),
                output: output.to_path_buf(),
                input: input.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Refuses a folder output (`option` names it) that would write over an input: `files` are the
/// files the command writes into it.
pub fn check_folder_output(
    inputs: &[&Path],
    option: &str,
    folder: &Path,
    files: &[PathBuf],
) -> Result<(), OutputError> {
    for file in files {
        if let Some(input) = inputs.iter().find(|input| same_file(file, input)) {
            return Err(OutputError::FolderOverInput {
                option: option.to_owned(),
                folder: folder.to_owned(),
                file: file.clone(),
                input: input.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Whether two paths name the same file: the same inode when both exist (links included),
/// else the same name in the same folder.
pub fn same_file(a: &Path, b: &Path) -> bool {
    // A page has no files; the name rule is all there is to it there.
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
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
        let dir = tempfile::tempdir().expect("a temporary folder");
        let input = dir.path().join("map.exr");
        std::fs::write(&input, b"x").expect("an input");
        let link = dir.path().join("link.exr");
        std::os::unix::fs::symlink(&input, &link).expect("a link");
        let other = dir.path().join("out.exr");
        assert!(check_outputs(&[&input], &[("-o", Some(&other))]).is_ok());
        for output in [&input, &link] {
            let e = check_outputs(&[&input], &[("-o", Some(output))]).expect_err("refused");
            assert!(e.to_string().contains("which this command reads"), "{e}");
        }
        let both = [
            ("-o", Some(other.as_path())),
            ("--png", Some(other.as_path())),
        ];
        let e = check_outputs(&[], &both).expect_err("refused");
        assert!(e.to_string().contains("name the same file"), "{e}");
        let files = [dir.path().join("map.exr")];
        let e = check_folder_output(&[&input], "-o", dir.path(), &files).expect_err("refused");
        assert!(e.to_string().contains("over"), "{e}");
    }
}
