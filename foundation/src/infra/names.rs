//! Names that become parts of file names (a scene's name in the bake cache, a probe's in
//! `probes/NAME.exr`): a name must stay one plain component of its folder.

/// Longest name: well inside every file system's 255-byte component once hprt adds its
/// suffixes (a bake's hash and settings).
pub const MAX_NAME_BYTES: usize = 100;

/// Refuses a name that would not stay one plain file name: empty, too long, with a path
/// separator, a control character (a newline, NUL) or a leading dot (`.`, `..`, hidden files).
/// `what` says whose name it is, for the message.
pub fn check_file_name(what: &str, name: &str) -> Result<(), String> {
    let problem = if name.is_empty() {
        Some("is empty".to_owned())
    } else if name.len() > MAX_NAME_BYTES {
        Some(format!(
            "is {} bytes long; at most {MAX_NAME_BYTES}",
            name.len()
        ))
    } else if name.contains(['/', '\\']) {
        Some("holds a path separator".to_owned())
    } else if name.chars().any(char::is_control) {
        Some("holds a control character".to_owned())
    } else if name.starts_with('.') {
        Some("begins with a dot".to_owned())
    } else {
        None
    };
    match problem {
        Some(problem) => Err(format!(
            "{what} {name:?} {problem}: a name becomes part of a file name in its own folder, \
             so it must be a plain name (letters, digits, spaces, '-', '_')"
        )),
        None => Ok(()),
    }
}

/// `name` as one plain file-name component whatever it holds (separators, control
/// characters and leading dots become `_`): for names checked elsewhere, so that a name that
/// escaped the check still cannot leave its folder.
pub fn as_file_name(name: &str) -> String {
    let mut out = String::new();
    for c in name.chars() {
        let c = match c {
            '/' | '\\' => '_',
            c if c.is_control() => '_',
            c => c,
        };
        // At most MAX_NAME_BYTES bytes, cut at a character's boundary.
        if out.len() + c.len_utf8() > MAX_NAME_BYTES {
            break;
        }
        out.push(c);
    }
    if out.is_empty() || out.starts_with('.') {
        out.insert(0, '_');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_would_leave_their_folder_are_refused() {
        for good in ["teapot", "room 2", "probe-1", "dragon_glossy", "a.b"] {
            assert!(check_file_name("name", good).is_ok(), "{good}");
        }
        for (bad, why) in [
            ("", "empty"),
            ("../escaped/evil", "separator"),
            ("/etc/cron.d/x", "separator"),
            ("..", "dot"),
            (".", "dot"),
            (".hidden", "dot"),
            ("a\\b", "separator"),
            ("a\nb", "control"),
            ("a\0b", "control"),
        ] {
            let e = check_file_name("scene name", bad).unwrap_err();
            assert!(
                e.contains(why) && e.starts_with("scene name"),
                "{bad:?}: {e}"
            );
        }
        assert!(check_file_name("name", &"x".repeat(MAX_NAME_BYTES)).is_ok());
        assert!(check_file_name("name", &"x".repeat(MAX_NAME_BYTES + 1)).is_err());
        for bad in ["../escaped/evil", "/abs", "..", "", "a\nb"] {
            let plain = as_file_name(bad);
            assert!(
                check_file_name("name", &plain).is_ok(),
                "{bad:?} -> {plain:?}"
            );
        }
        assert_eq!(as_file_name("teapot"), "teapot");
        assert_eq!(as_file_name(".."), "_..");
        let long = as_file_name(&"é".repeat(MAX_NAME_BYTES));
        assert!(long.len() <= MAX_NAME_BYTES && long.chars().all(|c| c == 'é'));
    }
}
