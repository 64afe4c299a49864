//! Loader messages for scenes the user gave as a dict: the library words its errors for a
//! TOML file, with line numbers; for a dict the TOML text is made by `Scene.from_dict` and
//! never seen, so its line numbers are taken out.

/// The name of a dict scene in messages, and its pseudo path (so meshes are found relative to
/// the current directory).
pub const DICT_PATH: &str = "<dict>";

/// A loader message about the generated text, without its line number: `line 7, `key`:
/// ...` → `` `key`: ...``, `line 7, cloth[0].damping: ...` → `cloth[0].damping: ...`, and
/// `line 7: ...` → ``at `<that line>`: ...``. Messages about other files (a mesh's lines)
/// are kept as they are.
pub fn without_lines(message: &str, text: &str) -> String {
    let Some((head, rest)) = message.split_once(": ") else {
        return message.to_string();
    };
    if head != DICT_PATH {
        return message.to_string();
    }
    let Some(after) = rest.strip_prefix("line ") else {
        return message.to_string();
    };
    let digits = after.bytes().take_while(u8::is_ascii_digit).count();
    if digits == 0 {
        return message.to_string();
    }
    let (number, tail) = after.split_at(digits);
    if let Some(tail) = tail.strip_prefix(", ") {
        return format!("{head}: {tail}");
    }
    if let Some(tail) = tail.strip_prefix(": ") {
        let line = number
            .parse::<usize>()
            .ok()
            .and_then(|n| text.lines().nth(n.checked_sub(1)?))
            .map(str::trim)
            .filter(|l| !l.is_empty());
        return match line {
            Some(l) => format!("{head}: at `{l}`: {tail}"),
            None => format!("{head}: {tail}"),
        };
    }
    message.to_string()
}

#[cfg(test)]
mod tests {
    use super::without_lines;

    #[test]
    fn line_numbers_of_the_generated_text_are_taken_out() {
        let text = "[simulation]\nduration = -1.0\n";
        assert_eq!(
            without_lines("<dict>: line 2, `duration`: bad", text),
            "<dict>: `duration`: bad"
        );
        assert_eq!(
            without_lines("<dict>: line 2, cloth[0].damping: must be ≥ 0", text),
            "<dict>: cloth[0].damping: must be ≥ 0"
        );
        assert_eq!(
            without_lines("<dict>: line 2: invalid type", text),
            "<dict>: at `duration = -1.0`: invalid type"
        );
        assert_eq!(
            without_lines("<dict>: no [[cloth]] table", text),
            "<dict>: no [[cloth]] table"
        );
        assert_eq!(
            without_lines("<dict>: lines are fine", text),
            "<dict>: lines are fine"
        );
        assert_eq!(
            without_lines("sheet.obj: line 2, bad face", text),
            "sheet.obj: line 2, bad face"
        );
    }
}
