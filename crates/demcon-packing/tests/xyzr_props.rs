//! Property tests of the `x y z r` reader: arbitrary and mutated text never panics; it is
//! either a clean error or particles with finite centres, positive finite radii and (when
//! the header names a container) inside it.

use demcon_core::Container;
use demcon_packing::{INSIDE_TOLERANCE, check_inside, parse_xyzr};
use proptest::prelude::*;

/// The invariant every accepted text must satisfy.
fn check_result(text: &str) -> Result<(), TestCaseError> {
    match parse_xyzr(text) {
        Err((line, message)) => {
            prop_assert!(line >= 1 && line <= text.lines().count().max(1), "line {line}");
            prop_assert!(!message.is_empty());
            prop_assert!(message.len() < 1000, "message too long: {message}");
        }
        Ok(f) => {
            prop_assert!(!f.particles.is_empty());
            for (c, &r) in f.particles.centres.iter().zip(&f.particles.radii) {
                prop_assert!(c.iter().all(|x| x.is_finite()));
                prop_assert!(r.is_finite() && r > 0.0);
            }
            if let Some(c) = &f.container {
                prop_assert!(check_inside(&f.particles, c).is_ok());
                prop_assert!(c.volume() > 0.0);
            }
        }
    }
    Ok(())
}

/// A valid file in a unit box: `n` spheres of radius 0.05 on a line.
fn valid_file(n: usize, kind: u8) -> String {
    let header = match kind % 4 {
        0 => "# container box 1 1 1",
        1 => "# container periodic 1 1 1",
        2 => "# container cylinder 0.5 1",
        _ => "# container sphere 0.5",
    };
    let mut s = format!("# demcon packing: one sphere per line, x y z r (m)\n{header}\n# count {n}\n");
    let z0 = if kind % 4 == 3 { -0.4 } else { 0.06 };
    let (x0, y0) = if kind % 4 >= 2 { (0.0, 0.0) } else { (0.5, 0.5) };
    for k in 0..n {
        s.push_str(&format!("{x0} {y0} {} 0.05\n", z0 + 0.11 * k as f64));
    }
    s
}

/// Token soup close to the file format: numbers (huge, tiny, negative, non-finite),
/// header words, separators.
fn token() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|x| x.to_string()),
        (-1.0f64..2.0).prop_map(|x| x.to_string()),
        prop::sample::select(vec![
            "#",
            "# container",
            "box",
            "periodic",
            "cylinder",
            "sphere",
            "# count",
            "count",
            "1e-308",
            "1e308",
            "4.9e-324",
            "-0",
            "nan",
            "inf",
            ",",
            "\t",
            " ",
            "\n",
            "\r\n",
            "x",
            "1e",
            "0.5",
        ])
        .prop_map(str::to_string),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
        check_result(&text)?;
    }

    #[test]
    fn token_soup_never_panics(tokens in prop::collection::vec(token(), 0..60)) {
        let text = tokens.join(" ");
        check_result(&text)?;
        check_result(&tokens.join("\n"))?;
    }

    #[test]
    fn mutated_valid_files_are_clean_errors_or_valid(
        n in 1usize..8,
        kind in 0u8..4,
        edits in prop::collection::vec((any::<prop::sample::Index>(), token(), 0u8..3), 1..6),
    ) {
        let original = valid_file(n, kind);
        prop_assert!(parse_xyzr(&original).is_ok(), "{original}");
        let mut text = original;
        for (at, tok, op) in edits {
            let mut i = at.index(text.len() + 1);
            while !text.is_char_boundary(i) {
                i -= 1;
            }
            match op {
                0 => text.insert_str(i, &tok),
                1 => text.truncate(i),
                _ => {
                    let mut j = (i + tok.len()).min(text.len());
                    while !text.is_char_boundary(j) {
                        j -= 1;
                    }
                    text.replace_range(i..j, &tok);
                }
            }
        }
        check_result(&text)?;
    }
}

#[test]
fn the_tolerance_is_small_and_stated() {
    const { assert!(INSIDE_TOLERANCE > 0.0 && INSIDE_TOLERANCE <= 0.01) };
    let f = parse_xyzr(&valid_file(3, 0)).unwrap();
    assert_eq!(f.container, Some(Container::Box { size: [1.0; 3] }));
}
