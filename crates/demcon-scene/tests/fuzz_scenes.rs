//! Property test of the scene loader: every example scene, mutated at random (bytes cut,
//! inserted or swapped, numbers replaced by extreme values), either loads and validates or
//! gives a clean error naming a line or a field — never a panic.

use std::path::{Path, PathBuf};

use demcon_scene::Scene;
use proptest::prelude::*;

fn examples() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut v: Vec<(String, String)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().and_then(|e| e.to_str()) == Some("ron"))
        .map(|p| (p.display().to_string(), std::fs::read_to_string(&p).unwrap()))
        .collect();
    v.sort();
    v
}

/// Values that broke earlier versions: zero, negative, huge, tiny, subnormal, non-finite.
const EXTREMES: &[&str] = &[
    "0",
    "0.0",
    "-1.0",
    "1e308",
    "1e-308",
    "4.9e-324",
    "NaN",
    "inf",
    "-inf",
    "18446744073709551615",
    "1e-70",
    "7.5e-30",
    "4294967296",
];

#[derive(Debug, Clone)]
enum Mutation {
    /// Cut the bytes [at, at + len).
    Cut { at: usize, len: usize },
    /// Insert a character.
    Insert { at: usize, c: char },
    /// Replace the k-th number by an extreme value.
    Number { k: usize, value: usize },
    /// Copy a slice elsewhere.
    Copy { from: usize, len: usize, to: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Cut { at, len }),
        (
            any::<usize>(),
            prop::sample::select(vec!['(', ')', '[', ']', ',', ':', '"', '-', '9', 'e', '.'])
        )
            .prop_map(|(at, c)| Mutation::Insert { at, c }),
        (any::<usize>(), 0..EXTREMES.len()).prop_map(|(k, value)| Mutation::Number { k, value }),
        (any::<usize>(), 1usize..60, any::<usize>()).prop_map(|(from, len, to)| Mutation::Copy {
            from,
            len,
            to
        }),
    ]
}

/// The char boundary at or before `i` (mod the length).
fn boundary(s: &str, i: usize) -> usize {
    let mut i = i % (s.len() + 1);
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &str, m: &Mutation) -> String {
    match *m {
        Mutation::Cut { at, len } => {
            let a = boundary(text, at);
            let b = boundary(text, (a + len).min(text.len()));
            format!("{}{}", &text[..a], &text[b.max(a)..])
        }
        Mutation::Insert { at, c } => {
            let a = boundary(text, at);
            format!("{}{c}{}", &text[..a], &text[a..])
        }
        Mutation::Number { k, value } => {
            // Numbers: maximal runs of digits, '.', 'e', '-' starting with a digit.
            let bytes = text.as_bytes();
            let mut spans = Vec::new();
            let mut i = 0;
            while i < bytes.len() {
                if bytes[i].is_ascii_digit() && (i == 0 || !bytes[i - 1].is_ascii_alphanumeric()) {
                    let start = i;
                    while i < bytes.len() && (bytes[i].is_ascii_digit() || b".e-+".contains(&bytes[i])) {
                        i += 1;
                    }
                    spans.push((start, i));
                } else {
                    i += 1;
                }
            }
            if spans.is_empty() {
                return text.to_string();
            }
            let (a, b) = spans[k % spans.len()];
            format!("{}{}{}", &text[..a], EXTREMES[value], &text[b..])
        }
        Mutation::Copy { from, len, to } => {
            let a = boundary(text, from);
            let b = boundary(text, (a + len).min(text.len())).max(a);
            let t = boundary(text, to);
            format!("{}{}{}", &text[..t], &text[a..b], &text[t..])
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_scenes_load_or_fail_cleanly(which in any::<usize>(), ms in prop::collection::vec(mutation(), 1..4)) {
        let all = examples();
        let (name, text) = &all[which % all.len()];
        let mut t = text.clone();
        for m in &ms {
            t = apply(&t, m);
        }
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        match Scene::parse(&t, Path::new(name), PathBuf::from(&base)) {
            Ok(scene) => {
                // A valid scene converts without error too.
                prop_assert!(demcon_scene::convert::problem(scene.config(), &base).is_ok());
            }
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(!msg.is_empty());
                prop_assert!(msg.len() < 2000, "overlong message: {msg}");
                prop_assert!(!msg.contains("0.000000000000"), "a number in 300 digits: {msg}");
            }
        }
    }
}
