//! Byte-level and token-level mutations (the mutation engine without any knowledge of glTF).
//!
//! Byte mutations are those of the classic coverage-free fuzzers (AFL's "havoc" stage): bit
//! flips, bytes and little-endian 16/32/64-bit words overwritten with boundary values, small
//! additions, random bytes, and ranges inserted, deleted, duplicated or copied, plus splicing
//! with a second corpus input. Text mutations work on tokens of the formats the targets read
//! (JSON, RON, `group.field=value`): numbers are replaced by boundary numbers, lines are
//! duplicated, deleted or swapped, identifiers are swapped with each other or with words of a
//! target's dictionary, and structural characters are inserted or removed. Every mutation is
//! total: it never panics, whatever the input, and keeps the input below `max_len` bytes.

use crate::rng::Rng;

/// Boundary values written as little-endian words: zero, one, all ones, the signed limits,
/// 2³¹ (the "2³¹-element accessor") and 2³² − 1, with the 16- and 64-bit analogues.
pub const INTERESTING_U64: &[u64] = &[
    0,
    1,
    2,
    3,
    4,
    0x7f,
    0x80,
    0xff,
    0x100,
    0x7fff,
    0x8000,
    0xffff,
    0x1_0000,
    1 << 22,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_fffe,
    0xffff_ffff,
    0x1_0000_0000,
    0x7fff_ffff_ffff_ffff,
    0x8000_0000_0000_0000,
    u64::MAX,
];

/// Interesting single bytes.
pub const INTERESTING_U8: &[u8] = &[0, 1, 0x7f, 0x80, 0xff, b'0', b'9', b'"', b'{', b'}', b'[', b']', b',', b':'];

/// Numbers in text form that break naive parsers: negative, zero, past f32's range (1e39),
/// not-a-number and infinities in several spellings, the 32-bit boundaries (2³¹, 2³² − 1),
/// the smallest f32 subnormal (1e-45), past u64, and exponents that overflow f64.
pub const INTERESTING_NUMBERS: &[&str] = &[
    "-1",
    "0",
    "-0",
    "1",
    "2",
    "3",
    "0.5",
    "-0.0",
    "1e39",
    "-1e39",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "Infinity",
    "1e308",
    "1e309",
    "-1e309",
    "1e-45",
    "1e-46",
    "4194304",
    "4194305",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483648",
    "-2147483649",
    "4294967295",
    "4294967296",
    "9007199254740993",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999999999",
    "0x10",
    "1.",
    ".5",
    "1e",
    "00",
    "+1",
];

/// Characters that open, close or separate structures in JSON and RON.
const STRUCTURAL: &[u8] = b"()[]{},:\"'=.#/*\\\n ";

/// Replaces `data` by one random byte-level mutation of itself (`other`: a second corpus
/// input for splicing). The result has at most `max_len` bytes.
pub fn mutate_bytes(rng: &mut Rng, data: &mut Vec<u8>, other: Option<&[u8]>, max_len: usize) {
    if data.is_empty() {
        let n = rng.small_len(16);
        data.extend((0..n).map(|_| rng.byte()));
        return;
    }
    let len = data.len();
    match rng.below(12) {
        0 => {
            let i = rng.below(len);
            data[i] ^= 1 << rng.below(8);
        }
        1 => {
            let i = rng.below(len);
            data[i] = *rng.pick(INTERESTING_U8).unwrap_or(&0);
        }
        2 => {
            let i = rng.below(len);
            data[i] = rng.byte();
        }
        3..=5 => {
            // A 16-, 32- or 64-bit boundary value, little-endian (GLB sizes and binary data are LE).
            let width = [2, 4, 4, 8][rng.below(4)];
            let value = *rng.pick(INTERESTING_U64).unwrap_or(&0);
            let bytes = value.to_le_bytes();
            let at = if rng.one_in(2) { rng.below(len) & !3 } else { rng.below(len) };
            for (k, b) in bytes.iter().take(width).enumerate() {
                if let Some(slot) = data.get_mut(at + k) {
                    *slot = *b;
                }
            }
        }
        6 => {
            // Small addition to a 32-bit little-endian word.
            let at = rng.below(len);
            if let Some(word) = data.get_mut(at..at + 4) {
                let v = u32::from_le_bytes([word[0], word[1], word[2], word[3]]);
                let delta = rng.range(1, 35) as u32;
                let v = if rng.one_in(2) { v.wrapping_add(delta) } else { v.wrapping_sub(delta) };
                word.copy_from_slice(&v.to_le_bytes());
            }
        }
        7 => {
            let n = rng.small_len(64).min(max_len.saturating_sub(len));
            let at = rng.below(len + 1);
            let fill: Vec<u8> = if rng.one_in(2) { vec![rng.byte(); n] } else { (0..n).map(|_| rng.byte()).collect() };
            data.splice(at..at, fill);
        }
        8 => {
            let n = rng.small_len(len);
            let at = rng.below(len - n + 1);
            data.drain(at..at + n);
        }
        9 => {
            // Duplicate a range somewhere else.
            let n = rng.small_len(len).min(max_len.saturating_sub(len));
            let from = rng.below(len - n + 1);
            let copy = data[from..from + n].to_vec();
            let at = rng.below(len + 1);
            data.splice(at..at, copy);
        }
        10 => {
            // Overwrite a range with a copy of another.
            let n = rng.small_len(len);
            let from = rng.below(len - n + 1);
            let to = rng.below(len - n + 1);
            data.copy_within(from..from + n, to);
        }
        _ => splice(rng, data, other, max_len),
    }
}

/// Splices `data` with `other`: a prefix of one, then a suffix of the other.
pub fn splice(rng: &mut Rng, data: &mut Vec<u8>, other: Option<&[u8]>, max_len: usize) {
    let Some(other) = other.filter(|o| !o.is_empty()) else { return };
    let cut = rng.below(data.len() + 1);
    let from = rng.below(other.len());
    data.truncate(cut);
    let room = max_len.saturating_sub(data.len());
    data.extend(other.iter().skip(from).take(room));
}

/// A token found in text: its byte range.
type Span = std::ops::Range<usize>;

/// The numbers in `text`: an optional sign, digits with an optional fraction and exponent.
pub fn number_spans(text: &[u8]) -> Vec<Span> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let start = i;
        let signed = matches!(text[i], b'-' | b'+') && text.get(i + 1).is_some_and(u8::is_ascii_digit);
        let prev_ident = i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_');
        if (signed || text[i].is_ascii_digit()) && !prev_ident {
            i += usize::from(signed);
            while i < text.len() && (text[i].is_ascii_digit() || matches!(text[i], b'.' | b'e' | b'E')) {
                let exp_sign = matches!(text[i], b'e' | b'E') && matches!(text.get(i + 1), Some(b'-' | b'+'));
                i += 1 + usize::from(exp_sign);
            }
            spans.push(start..i);
        } else {
            i += 1;
        }
    }
    spans
}

/// The identifiers in `text` (a letter or `_`, then letters, digits and `_`; not the
/// exponent of a number).
pub fn identifier_spans(text: &[u8]) -> Vec<Span> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        if text[i].is_ascii_digit() {
            // A number, with its fraction and exponent.
            while i < text.len() && (text[i].is_ascii_alphanumeric() || text[i] == b'.') {
                let exp_sign = matches!(text[i], b'e' | b'E') && matches!(text.get(i + 1), Some(b'-' | b'+'));
                i += 1 + usize::from(exp_sign);
            }
        } else if text[i].is_ascii_alphabetic() || text[i] == b'_' {
            let start = i;
            while i < text.len() && (text[i].is_ascii_alphanumeric() || text[i] == b'_') {
                i += 1;
            }
            spans.push(start..i);
        } else {
            i += 1;
        }
    }
    spans
}

/// The lines of `text`, each with its newline.
fn line_spans(text: &[u8]) -> Vec<Span> {
    let mut spans = Vec::new();
    let mut start = 0;
    for (i, b) in text.iter().enumerate() {
        if *b == b'\n' {
            spans.push(start..i + 1);
            start = i + 1;
        }
    }
    if start < text.len() {
        spans.push(start..text.len());
    }
    spans
}

/// A number as text: a boundary number, a power of two, or a small random integer.
pub fn interesting_number(rng: &mut Rng) -> String {
    match rng.below(4) {
        0 | 1 => rng.pick(INTERESTING_NUMBERS).copied().unwrap_or("0").to_string(),
        2 => {
            let p = 1u128 << rng.below(65);
            let off = [0i128, -1, 1][rng.below(3)];
            (p as i128 + off).to_string()
        }
        _ => rng.below(300).to_string(),
    }
}

/// Replaces `data` by one random token-level mutation of itself; `dictionary` holds words
/// of the target's format (field names, choice names, glTF keys) that are inserted or swapped
/// in. Falls back to a byte mutation when the chosen token kind does not occur.
pub fn mutate_text(rng: &mut Rng, data: &mut Vec<u8>, dictionary: &[&str], other: Option<&[u8]>, max_len: usize) {
    let done = match rng.below(9) {
        0..=2 => replace_number(rng, data),
        3 => lines(rng, data, max_len),
        4 | 5 => identifiers(rng, data, dictionary),
        6 => {
            // Insert a dictionary word or a structural character.
            let at = rng.below(data.len() + 1);
            let word: Vec<u8> = match rng.pick(dictionary) {
                Some(w) if rng.one_in(2) => w.as_bytes().to_vec(),
                _ => vec![*rng.pick(STRUCTURAL).unwrap_or(&b',')],
            };
            if data.len() + word.len() <= max_len {
                data.splice(at..at, word);
            }
            true
        }
        7 => {
            // Remove one structural character (unbalances brackets, joins tokens).
            let positions: Vec<usize> = (0..data.len()).filter(|&i| STRUCTURAL.contains(&data[i])).collect();
            match rng.pick(&positions) {
                Some(&i) => {
                    data.remove(i);
                    true
                }
                None => false,
            }
        }
        _ => {
            // Copy a token (number or identifier) over another one of the same kind.
            let spans = if rng.one_in(2) { number_spans(data) } else { identifier_spans(data) };
            match (rng.pick(&spans).cloned(), rng.pick(&spans).cloned()) {
                (Some(a), Some(b)) if a != b => {
                    let word = data[a].to_vec();
                    data.splice(b, word);
                    true
                }
                _ => false,
            }
        }
    };
    if !done {
        mutate_bytes(rng, data, other, max_len);
    }
    data.truncate(max_len);
}

/// Replaces one number of `data` with an interesting number.
fn replace_number(rng: &mut Rng, data: &mut Vec<u8>) -> bool {
    let spans = number_spans(data);
    let Some(span) = rng.pick(&spans).cloned() else { return false };
    let n = interesting_number(rng);
    data.splice(span, n.into_bytes());
    true
}

/// Duplicates, deletes or swaps lines.
fn lines(rng: &mut Rng, data: &mut Vec<u8>, max_len: usize) -> bool {
    let spans = line_spans(data);
    if spans.len() < 2 {
        return false;
    }
    let (Some(a), Some(b)) = (rng.pick(&spans).cloned(), rng.pick(&spans).cloned()) else { return false };
    match rng.below(3) {
        0 => {
            let n = rng.small_len(8);
            let copies: Vec<u8> = data[a.clone()].repeat(n);
            if data.len() + copies.len() <= max_len {
                data.splice(b.start..b.start, copies);
            }
        }
        1 => {
            data.drain(a);
        }
        _ => {
            let (first, second) = if a.start <= b.start { (a, b) } else { (b, a) };
            if first.end <= second.start {
                let mut out = data[..first.start].to_vec();
                out.extend_from_slice(&data[second.clone()]);
                out.extend_from_slice(&data[first.end..second.start]);
                out.extend_from_slice(&data[first]);
                out.extend_from_slice(&data[second.end..]);
                *data = out;
            }
        }
    }
    true
}

/// Swaps two identifiers of `data`, or replaces one with a dictionary word.
fn identifiers(rng: &mut Rng, data: &mut Vec<u8>, dictionary: &[&str]) -> bool {
    let spans = identifier_spans(data);
    let Some(a) = rng.pick(&spans).cloned() else { return false };
    if rng.one_in(2)
        && let Some(word) = rng.pick(dictionary)
    {
        data.splice(a, word.bytes());
        return true;
    }
    let Some(b) = rng.pick(&spans).cloned() else { return false };
    if a == b {
        return false;
    }
    let (first, second) = if a.start < b.start { (a, b) } else { (b, a) };
    let (w1, w2) = (data[first.clone()].to_vec(), data[second.clone()].to_vec());
    data.splice(second, w1);
    data.splice(first, w2);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_found() {
        let t = b"(a: -1.5e-3, b_2: 7, \"c\": [1,2]) x9";
        let numbers: Vec<&[u8]> = number_spans(t).into_iter().map(|s| &t[s]).collect();
        assert_eq!(numbers, [&b"-1.5e-3"[..], b"7", b"1", b"2"]);
        let idents: Vec<&[u8]> = identifier_spans(t).into_iter().map(|s| &t[s]).collect();
        assert_eq!(idents, [&b"a"[..], b"b_2", b"c", b"x9"]);
        assert_eq!(line_spans(b"a\nb\n\nc"), [0..2, 2..4, 4..5, 5..6]);
    }

    #[test]
    fn mutations_are_total_and_bounded() {
        let mut rng = Rng::new(3);
        let seeds: [&[u8]; 4] = [b"", b"x", b"(a: 1, b: [2, 3])\n(c: d)\n", &[0xff; 40]];
        for seed in seeds {
            for _ in 0..2000 {
                let mut d = seed.to_vec();
                for _ in 0..rng.small_len(8) {
                    mutate_bytes(&mut rng, &mut d, Some(b"spliced"), 64);
                    assert!(d.len() <= 64);
                    mutate_text(&mut rng, &mut d, &["word", "other"], Some(b"1,2"), 64);
                    assert!(d.len() <= 64);
                }
            }
        }
    }
}
