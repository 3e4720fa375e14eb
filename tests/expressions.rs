//! The "Expression language" section of docs/scenes.md, checked against the implementation: every row of
//! its examples table is evaluated (or must fail with the documented column and message), and
//! the variables, functions and constants it lists are exactly the ones the parser accepts.

use hvi::scene::{
    Expr, BINARY_FUNCTIONS, BODY_FORCE_VARIABLES, CONSTANTS, FUNCTIONS, KERNEL_VARIABLES, TRACTION_VARIABLES,
};

fn section() -> String {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scenes.md")).unwrap();
    let start = readme
        .find("### Expression language")
        .expect("docs/scenes.md has the section");
    let rest = &readme[start + 4..];
    let end = rest.find("\n#").unwrap_or(rest.len());
    rest[..end].to_string()
}

/// The cells of a markdown table row (`\|` is a literal bar inside a cell).
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner
        .replace("\\|", "\u{0}")
        .split('|')
        .map(|c| c.replace('\u{0}', "|").trim().to_string())
        .collect()
}

fn code(cell: &str) -> String {
    cell.trim_matches('`').to_string()
}

const ALL: [&str; 8] = ["x", "y", "z", "t", "nx", "ny", "nz", "s"];

#[test]
fn every_documented_example_evaluates_as_documented() {
    let text = section();
    let table = &text[text.find("Examples (tests/expressions.rs").unwrap()..];
    let mut checked = 0;
    for line in table.lines().filter(|l| l.starts_with("| `")) {
        let c = cells(line);
        assert_eq!(c.len(), 3, "{line}");
        let source = code(&c[0]);
        let mut values = [0.0; 8];
        for assignment in c[1].split(',').filter(|a| !a.trim().is_empty()) {
            let (name, value) = assignment.split_once('=').unwrap();
            let i = ALL.iter().position(|v| *v == name.trim()).unwrap();
            values[i] = value.trim().parse().unwrap();
        }
        match c[2].strip_prefix("error: ") {
            Some(expected) => {
                let (column, says) = expected.split_once(": ").unwrap();
                let e = Expr::parse(&source, &ALL).expect_err(&source);
                assert!(e.starts_with(&format!("{column}:")), "{source}: {e}");
                assert!(e.contains(says), "{source}: {e}");
            }
            None => {
                let want: f64 = c[2].parse().unwrap();
                let got = Expr::parse(&source, &ALL)
                    .unwrap_or_else(|e| panic!("{source}: {e}"))
                    .eval(&values);
                // the README prints 15 significant digits
                assert!(
                    (got - want).abs() <= 1e-14 * (1.0 + want.abs()),
                    "{source}: {got} vs {want}"
                );
            }
        }
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} examples found");
}

#[test]
fn the_listed_variables_functions_and_constants_are_the_accepted_ones() {
    let text = section();
    let row = |starts: &str| -> Vec<String> {
        let line = text
            .lines()
            .find(|l| l.starts_with(starts))
            .unwrap_or_else(|| panic!("{starts}"));
        let last = cells(line).pop().unwrap();
        last.split('`').skip(1).step_by(2).map(str::to_string).collect()
    };
    assert_eq!(row("| `[[traction]] value`"), TRACTION_VARIABLES);
    assert_eq!(row("| `[body_force] value`"), BODY_FORCE_VARIABLES);
    assert_eq!(row("| `[memory] kind"), KERNEL_VARIABLES);
    let listed = text.lines().find(|l| l.starts_with("`abs ")).unwrap().trim_matches('`');
    assert_eq!(listed.split(' ').collect::<Vec<_>>(), FUNCTIONS);
    for f in FUNCTIONS {
        assert!(Expr::parse(&format!("{f}(0.5)"), &["x"]).is_ok(), "{f}");
    }
    for f in BINARY_FUNCTIONS {
        assert!(text.contains(&format!("`{f}(")), "{f}");
        assert!(Expr::parse(&format!("{f}(0.5, 1)"), &["x"]).is_ok(), "{f}");
    }
    for c in CONSTANTS {
        assert!(text.contains(&format!("`{c}`")), "{c}");
        assert!(Expr::parse(c, &["x"]).is_ok(), "{c}");
    }
    // the error shown in the README is the one hvi gives
    let e = Expr::parse("x > 0.99 ? 1 : 0", &["x"]).unwrap_err();
    let shown: Vec<&str> = e.lines().skip(1).collect();
    assert!(text.contains(&shown.join("\n")), "{e}");
}
