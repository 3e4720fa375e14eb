//! Expressions in a scene (loads in x, y, t; kernels in s), compiled once with exmex and
//! evaluated many times. exmex orders variables alphabetically; [`Expr`] maps them to the
//! order the caller declares.
//!
//! Two exmex conventions would surprise a user, so they are handled here:
//! * its default literals have no exponent: `1e-3` is accepted through [`SciNumber`];
//! * its unary minus binds tighter than `^` (`-x^2` would be (−x)²): such an expression is
//!   rejected with a message asking for `-(x^2)` or `(-x)^2` ([`check_unary_minus_power`]);
//! * its `^` associates to the left (`2^3^2` would be 64): chained powers must be bracketed
//!   ([`check_chained_powers`]).

use exmex::prelude::*;
use exmex::{literal_matcher_from_pattern, FlatEx, FloatOpsFactory, MatchLiteral};

literal_matcher_from_pattern!(SciNumber, r"^(([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?)");

type Flat = FlatEx<f64, FloatOpsFactory<f64>, SciNumber>;

/// The variables of a traction density: the point (x, y, z), the time t and the facet's outward
/// unit normal (nx, ny, nz). In 2D, z = nz = 0. A load on a group that has several sides can use
/// the normal to tell them apart: the paper's Γ₂ load is `-0.1*(1 - exp(-2*t))*x*ny`, zero on the
/// right side (ny = 0) and the paper's load on the top (ny = 1).
pub const TRACTION_VARIABLES: [&str; 7] = ["x", "y", "z", "t", "nx", "ny", "nz"];

/// The variables of a body force density: the point (x, y, z) and the time t (z = 0 in 2D).
pub const BODY_FORCE_VARIABLES: [&str; 4] = ["x", "y", "z", "t"];

/// Rejects a unary minus whose operand is raised to a power (`-x^2`, `2*-(a+b)^3`), which exmex
/// would read as (−x)², unlike the usual convention. Returns the column (1-based) of the minus.
fn check_unary_minus_power(source: &str) -> Result<(), String> {
    let chars: Vec<char> = source.chars().collect();
    let skip_ws = |mut i: usize| {
        while i < chars.len() && chars[i].is_whitespace() {
            i += 1;
        }
        i
    };
    let mut expect_operand = true;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        if expect_operand && c == '-' {
            // find the end of the operand that follows
            let mut j = skip_ws(i + 1);
            while j < chars.len() && (chars[j] == '-' || chars[j] == '+') {
                j = skip_ws(j + 1);
            }
            while j < chars.len() && (chars[j].is_alphanumeric() || chars[j] == '_' || chars[j] == '.') {
                // a literal like 1e-3 carries its own sign
                if (chars[j] == 'e' || chars[j] == 'E')
                    && j + 1 < chars.len()
                    && (chars[j + 1] == '-' || chars[j + 1] == '+')
                    && j > 0
                    && chars[j - 1].is_ascii_digit()
                {
                    j += 1;
                }
                j += 1;
            }
            j = skip_ws(j);
            if j < chars.len() && chars[j] == '(' {
                let mut depth = 0;
                while j < chars.len() {
                    match chars[j] {
                        '(' => depth += 1,
                        ')' => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        _ => {}
                    }
                    j += 1;
                }
                j = skip_ws(j + 1);
            }
            if j < chars.len() && chars[j] == '^' {
                return Err(format!(
                    "column {}: a minus sign in front of a power is ambiguous here (it would be applied before the power); write -({}) for the negative of the power, or put the sign inside parentheses",
                    i + 1,
                    chars[i + 1..].iter().collect::<String>().trim()
                ));
            }
            i += 1;
            continue;
        }
        expect_operand = matches!(c, '(' | ',' | '+' | '-' | '*' | '/' | '^');
        i += 1;
    }
    Ok(())
}

/// Rejects chained powers `a^b^c` without parentheses, which exmex evaluates left to right
/// ((a^b)^c) unlike the usual right-to-left convention.
fn check_chained_powers(source: &str) -> Result<(), String> {
    // per parenthesis depth: was the last binary operator at this depth a power?
    let mut last_was_power = vec![false];
    for (i, c) in source.chars().enumerate() {
        match c {
            '(' => last_was_power.push(false),
            ')' if last_was_power.len() > 1 => {
                last_was_power.pop();
            }
            '+' | '-' | '*' | '/' | ',' => {
                if let Some(top) = last_was_power.last_mut() {
                    *top = false;
                }
            }
            '^' => {
                let top = last_was_power.last_mut().expect("depth 0 is never popped");
                if *top {
                    return Err(format!(
                        "column {}: chained powers a^b^c are ambiguous here (they would be read as (a^b)^c); write (a^b)^c or a^(b^c)",
                        i + 1
                    ));
                }
                *top = true;
            }
            _ => {}
        }
    }
    Ok(())
}

/// A compiled scalar expression over a declared list of variables.
#[derive(Clone, Debug)]
pub struct Expr {
    source: String,
    flat: Flat,
    /// For each exmex variable (alphabetical), its index in the caller's variable list.
    order: Vec<usize>,
    used: Vec<String>,
}

impl Expr {
    /// Compiles `source`; every variable must be one of `allowed_vars`.
    pub fn parse(source: &str, allowed_vars: &[&str]) -> Result<Expr, String> {
        if source.trim().is_empty() {
            return Err("the expression is empty".into());
        }
        check_unary_minus_power(source)?;
        check_chained_powers(source)?;
        let flat = Flat::parse(source).map_err(|e| format!("cannot parse: {}", e.msg()))?;
        let mut order = Vec::new();
        let mut used = Vec::new();
        for name in flat.var_names() {
            match allowed_vars.iter().position(|v| v == name) {
                Some(i) => order.push(i),
                None => {
                    return Err(format!(
                        "unknown variable `{name}`; the variables here are {}",
                        allowed_vars
                            .iter()
                            .map(|v| format!("`{v}`"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ))
                }
            }
            used.push(name.clone());
        }
        Ok(Expr {
            source: source.to_string(),
            flat,
            order,
            used,
        })
    }

    /// The value at `values` (in the order of the declared variables). NaN if evaluation fails.
    pub fn eval(&self, values: &[f64]) -> f64 {
        let mut vars = [0.0; 8];
        for (k, &i) in self.order.iter().enumerate() {
            vars[k] = values[i];
        }
        self.flat.eval(&vars[..self.order.len()]).unwrap_or(f64::NAN)
    }

    /// True if the expression uses variable `var`.
    pub fn depends_on(&self, var: &str) -> bool {
        self.used.iter().any(|v| v == var)
    }

    /// The text it was compiled from.
    pub fn source(&self) -> &str {
        &self.source
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variables_follow_the_declared_order() {
        let e = Expr::parse("-0.1*(1 - exp(-2*t))*x + y^2", &["x", "y", "t"]).unwrap();
        let (x, y, t) = (1.5f64, 0.5f64, 0.3f64);
        assert!((e.eval(&[x, y, t]) - (-0.1 * (1.0 - (-2.0 * t).exp()) * x + y * y)).abs() < 1e-15);
        assert!(e.depends_on("t") && !Expr::parse("x", &["x", "y", "t"]).unwrap().depends_on("t"));
        assert!(Expr::parse("z + 1", &["x", "y", "t"]).unwrap_err().contains("`z`"));
        assert!(Expr::parse("sin(", &["x"]).is_err());
        assert_eq!(Expr::parse("2", &["x", "y", "t"]).unwrap().eval(&[0.0, 0.0, 0.0]), 2.0);
        // scientific literals
        assert_eq!(
            Expr::parse("1.5e-3*x + 2E2", &["x"]).unwrap().eval(&[2.0]),
            3e-3 + 200.0
        );
        assert_eq!(
            Expr::parse("-1.0989010989010988e-2", &["x"]).unwrap().eval(&[0.0]),
            -1.0989010989010988e-2
        );
        // a minus before a power is rejected, not silently read as (−x)²
        for bad in ["-x^2", "2*-x^2", "-(x+1)^2", "exp(-x^2)", "- 2 ^ 2"] {
            assert!(Expr::parse(bad, &["x"]).unwrap_err().contains("minus"), "{bad}");
        }
        assert_eq!(Expr::parse("-(x^2)", &["x"]).unwrap().eval(&[3.0]), -9.0);
        assert!(Expr::parse("2^3^2", &["x"]).unwrap_err().contains("chained"));
        assert_eq!(Expr::parse("2^(3^2)", &["x"]).unwrap().eval(&[0.0]), 512.0);
        assert_eq!(Expr::parse("(2^3)^2 + x^2*x^2", &["x"]).unwrap().eval(&[1.0]), 65.0);
        assert_eq!(
            Expr::parse("exp(x^2) + y^2", &["x", "y"]).unwrap().eval(&[0.0, 2.0]),
            5.0
        );
        assert_eq!(Expr::parse("x-2^2", &["x"]).unwrap().eval(&[3.0]), -1.0);
        assert_eq!(Expr::parse("x^-2", &["x"]).unwrap().eval(&[2.0]), 0.25);
        assert_eq!(Expr::parse("exp(-2*x)", &["x"]).unwrap().eval(&[0.0]), 1.0);
    }
}
