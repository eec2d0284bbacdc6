//! A clearer word for the commonest mistake in a hand-edited TOML file: a bare word as a value
//! (`fps = ten`, `method = icgn1`), which the TOML parser can only report as what the word's
//! first letter made it expect ("invalid boolean, expected `true`", "invalid number").

/// The hint for a parse error at byte `offset` of `text`, when a bare word (up to a space, a
/// comma, a closing bracket or brace, a comment or a quote; starting with a letter) other than
/// `true`, `false`, `inf` or `nan` starts there.
pub fn bare_word_hint(text: &str, offset: usize) -> Option<String> {
    let rest = text.get(offset..)?;
    let word: String = rest
        .chars()
        .take_while(|c| !c.is_whitespace() && !matches!(c, ',' | ']' | '}' | '#' | '"' | '\''))
        .collect();
    let first = word.chars().next()?;
    if !first.is_ascii_alphabetic() || matches!(word.as_str(), "true" | "false" | "inf" | "nan") {
        return None;
    }
    Some(format!(
        "`{word}` is not a TOML value: numbers are written in digits (10, 0.5), words in quotes \
         (\"{word}\")"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bare_word_gets_a_hint_and_nothing_else_does() {
        let text = "fps = ten\nmethod = icgn1\nok = true\nn = 12\ns = \"x\"";
        let hint = bare_word_hint(text, 6).unwrap();
        assert!(hint.starts_with("`ten` is not a TOML value"), "{hint}");
        assert!(bare_word_hint(text, text.find("icgn1").unwrap())
            .unwrap()
            .contains("(\"icgn1\")"));
        for at in ["true", "12", "\"x\""] {
            assert_eq!(bare_word_hint(text, text.find(at).unwrap()), None, "{at}");
        }
        assert_eq!(bare_word_hint(text, text.len() + 3), None);
    }
}
