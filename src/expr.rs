//! Expressions in a scene (loads in x, y, z, t and the facet normal; kernels in s;
//! docs/scenes.md "Expression language", docs/method.md §11.1), compiled once and evaluated many times.
//!
//! hvi parses an expression itself, with the grammar docs/scenes.md documents, so that every error
//! names its column (with a caret under it) and says what is valid there; the checked tree is
//! compiled into a tree of closures over f64 (numbers parsed once, constants and variables
//! resolved to values and slots) and evaluated directly. One parser: nothing is printed and read
//! again. The arithmetic is IEEE's and the functions are Rust's `f64` methods (`^` is `powf`,
//! `log` and `ln` the natural logarithm).
//!
//! Precedence, loosest first: `a if c else b`, `||`, `&&`, comparisons `< <= > >= == !=`,
//! `+ -`, `* /`, unary `- + !`, `^`, then numbers, variables, constants, `f(…)` and `(…)`.
//! Comparisons and logical operators give 1 (true) or 0 (false); any non-zero value is true.
//! Three readings differ between tools, so hvi refuses them and asks for parentheses:
//! * a sign in front of a power (`-x^2`: −(x²) or (−x)²?);
//! * chained powers (`2^3^2`: 2⁹ or 8²?);
//! * chained comparisons (`0 < x < 1`: write `0 < x && x < 1`).
//!
//! Over 600 lines because it is one language: tokens, the grammar with its messages, the compiled
//! code, and some 120 lines of tests.

fn truth(a: f64) -> bool {
    a != 0.0
}

fn bool_value(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

/// The variables of a traction density: the point (x, y, z), the time t and the facet's outward
/// unit normal (nx, ny, nz). In 2D, z = nz = 0. A load on a group that has several sides can use
/// the normal to tell them apart: the paper's Γ₂ load is `-0.1*(1 - exp(-2*t))*x*ny`, zero on the
/// right side (ny = 0) and the paper's load on the top (ny = 1). A pressure has the same ones.
pub const TRACTION_VARIABLES: [&str; 7] = ["x", "y", "z", "t", "nx", "ny", "nz"];

/// The variables of a body force density: the point (x, y, z) and the time t (z = 0 in 2D).
/// Prescribed displacements have the same ones.
pub const BODY_FORCE_VARIABLES: [&str; 4] = ["x", "y", "z", "t"];

/// The variable of a relaxation kernel b(s): the time lag s ≥ 0.
pub const KERNEL_VARIABLES: [&str; 1] = ["s"];

/// The functions of one argument (`log` and `ln` are both the natural logarithm).
pub const FUNCTIONS: [&str; 26] = [
    "abs", "signum", "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh",
    "floor", "round", "ceil", "trunc", "fract", "exp", "sqrt", "cbrt", "ln", "log", "log2", "log10",
];

/// The functions of two arguments: atan2(y, x), min(a, b), max(a, b).
pub const BINARY_FUNCTIONS: [&str; 3] = ["atan2", "min", "max"];

/// The named constants: π (also `PI`), e (also `E`), τ = 2π (also `TAU`).
pub const CONSTANTS: [&str; 6] = ["PI", "π", "E", "e", "TAU", "τ"];

/// A token and the column (1-based, in characters) where it starts.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(String),
    Name(String),
    Op(&'static str),
    Open,
    Close,
    Comma,
    End,
}

const OPERATORS: [&str; 14] = [
    "<=", ">=", "==", "!=", "&&", "||", "<", ">", "!", "+", "-", "*", "/", "^",
];

/// An error at `col` of `source`: the message, the source and a caret under the column.
fn at(source: &str, col: usize, message: impl std::fmt::Display) -> String {
    let line: String = source
        .chars()
        .map(|c| if c.is_whitespace() { ' ' } else { c })
        .collect();
    format!(
        "column {col}: {message}\n    {line}\n    {}^",
        " ".repeat(col.saturating_sub(1))
    )
}

fn tokenize(source: &str) -> Result<Vec<(Tok, usize)>, String> {
    let chars: Vec<char> = source.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit())) {
            let start = i;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
            if i < chars.len() && chars[i] == '.' {
                i += 1;
                while i < chars.len() && chars[i].is_ascii_digit() {
                    i += 1;
                }
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    while j < chars.len() && chars[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            out.push((Tok::Num(chars[start..i].iter().collect()), col));
            continue;
        }
        if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((Tok::Name(chars[start..i].iter().collect()), col));
            continue;
        }
        match c {
            '(' => out.push((Tok::Open, col)),
            ')' => out.push((Tok::Close, col)),
            ',' => out.push((Tok::Comma, col)),
            _ => {
                let two: String = chars[i..(i + 2).min(chars.len())].iter().collect();
                if let Some(op) = OPERATORS.iter().find(|op| two.starts_with(*op)) {
                    out.push((Tok::Op(op), col));
                    i += op.chars().count();
                    continue;
                }
                let hint = match c {
                    '=' => "`=` alone is not an operator: write `==` for equality".to_string(),
                    '&' => "write `&&` for a logical and".to_string(),
                    '|' => "write `||` for a logical or".to_string(),
                    _ => format!(
                        "`{c}` is not part of the language; the operators are {}, and the conditional `a if c else b`",
                        OPERATORS.map(|o| format!("`{o}`")).join(" ")
                    ),
                };
                return Err(at(source, col, hint));
            }
        }
        i += 1;
    }
    out.push((Tok::End, chars.len() + 1));
    Ok(out)
}

/// A checked expression tree.
#[derive(Clone, Debug)]
enum Node {
    Leaf(String),
    Unary(&'static str, Box<Node>),
    Binary(&'static str, Box<Node>, Box<Node>),
    Call(String, Vec<Node>),
    Group(Box<Node>),
    /// then, condition, otherwise
    Cond(Box<Node>, Box<Node>, Box<Node>),
}

/// A compiled expression: what [`Expr::eval`] walks.
#[derive(Clone, Debug)]
enum Code {
    Number(f64),
    /// The caller's variable at this index.
    Variable(usize),
    Unary(fn(f64) -> f64, Box<Code>),
    Binary(fn(f64, f64) -> f64, Box<Code>, Box<Code>),
    /// then, condition, otherwise
    Cond(Box<Code>, Box<Code>, Box<Code>),
}

impl Code {
    fn eval(&self, values: &[f64]) -> f64 {
        match self {
            Code::Number(v) => *v,
            Code::Variable(i) => values[*i],
            Code::Unary(f, a) => f(a.eval(values)),
            Code::Binary(f, a, b) => f(a.eval(values), b.eval(values)),
            Code::Cond(a, c, b) => {
                // every branch is evaluated, as the operators of the grammar are
                let (a, c, b) = (a.eval(values), c.eval(values), b.eval(values));
                if truth(c) {
                    a
                } else {
                    b
                }
            }
        }
    }
}

/// The function of a unary operator or a one-argument function.
fn unary_function(name: &str) -> Option<fn(f64) -> f64> {
    Some(match name {
        "-" => |a: f64| -a,
        "+" => |a| a,
        "!" => |a| bool_value(!truth(a)),
        "abs" => f64::abs,
        "signum" => f64::signum,
        "sin" => f64::sin,
        "cos" => f64::cos,
        "tan" => f64::tan,
        "asin" => f64::asin,
        "acos" => f64::acos,
        "atan" => f64::atan,
        "sinh" => f64::sinh,
        "cosh" => f64::cosh,
        "tanh" => f64::tanh,
        "asinh" => f64::asinh,
        "acosh" => f64::acosh,
        "atanh" => f64::atanh,
        "floor" => f64::floor,
        "round" => f64::round,
        "ceil" => f64::ceil,
        "trunc" => f64::trunc,
        "fract" => f64::fract,
        "exp" => f64::exp,
        "sqrt" => f64::sqrt,
        "cbrt" => f64::cbrt,
        "ln" | "log" => f64::ln,
        "log2" => f64::log2,
        "log10" => f64::log10,
        _ => return None,
    })
}

/// The function of a binary operator or a two-argument function.
fn binary_function(name: &str) -> Option<fn(f64, f64) -> f64> {
    Some(match name {
        "+" => |a: f64, b: f64| a + b,
        "-" => |a, b| a - b,
        "*" => |a, b| a * b,
        "/" => |a, b| a / b,
        "^" => f64::powf,
        "<" => |a, b| bool_value(a < b),
        "<=" => |a, b| bool_value(a <= b),
        ">" => |a, b| bool_value(a > b),
        ">=" => |a, b| bool_value(a >= b),
        "==" => |a, b| bool_value(a == b),
        "!=" => |a, b| bool_value(a != b),
        "&&" => |a, b| bool_value(truth(a) && truth(b)),
        "||" => |a, b| bool_value(truth(a) || truth(b)),
        "atan2" => f64::atan2,
        "min" => f64::min,
        "max" => f64::max,
        _ => return None,
    })
}

impl Node {
    /// The tree as code over the caller's variables (`vars`); `used` collects the variables it
    /// reads. Every name was checked by the parser.
    fn compile(&self, vars: &[&str], used: &mut Vec<String>) -> Result<Code, String> {
        let missing = |what: &str, name: &str| format!("cannot compile the {what} `{name}`");
        Ok(match self {
            Node::Leaf(text) => match text.as_str() {
                "PI" | "π" => Code::Number(std::f64::consts::PI),
                "E" | "e" => Code::Number(std::f64::consts::E),
                "TAU" | "τ" => Code::Number(std::f64::consts::TAU),
                name => match vars.iter().position(|v| *v == name) {
                    Some(i) => {
                        if !used.iter().any(|u| u == name) {
                            used.push(name.to_string());
                        }
                        Code::Variable(i)
                    }
                    None => Code::Number(name.parse().map_err(|_| missing("number", name))?),
                },
            },
            Node::Unary(op, a) => Code::Unary(
                unary_function(op).ok_or_else(|| missing("operator", op))?,
                Box::new(a.compile(vars, used)?),
            ),
            Node::Binary(op, a, b) => Code::Binary(
                binary_function(op).ok_or_else(|| missing("operator", op))?,
                Box::new(a.compile(vars, used)?),
                Box::new(b.compile(vars, used)?),
            ),
            Node::Call(f, args) => match &args[..] {
                [a] => Code::Unary(
                    unary_function(f).ok_or_else(|| missing("function", f))?,
                    Box::new(a.compile(vars, used)?),
                ),
                [a, b] => Code::Binary(
                    binary_function(f).ok_or_else(|| missing("function", f))?,
                    Box::new(a.compile(vars, used)?),
                    Box::new(b.compile(vars, used)?),
                ),
                _ => return Err(missing("call", f)),
            },
            Node::Group(a) => a.compile(vars, used)?,
            Node::Cond(a, c, b) => Code::Cond(
                Box::new(a.compile(vars, used)?),
                Box::new(c.compile(vars, used)?),
                Box::new(b.compile(vars, used)?),
            ),
        })
    }
}

struct Parser<'a> {
    source: &'a str,
    toks: Vec<(Tok, usize)>,
    pos: usize,
    vars: &'a [&'a str],
}

const OPERAND: &str = "a number, a variable, a constant, a function call such as exp(…) or a `(`";

impl Parser<'_> {
    fn peek(&self) -> &Tok {
        &self.toks[self.pos].0
    }
    fn col(&self) -> usize {
        self.toks[self.pos].1
    }
    fn err(&self, message: impl std::fmt::Display) -> String {
        at(self.source, self.col(), message)
    }
    fn is_op(&self, op: &str) -> bool {
        matches!(self.peek(), Tok::Op(o) if *o == op)
    }
    fn is_name(&self, name: &str) -> bool {
        matches!(self.peek(), Tok::Name(n) if n == name)
    }
    fn variables(&self) -> String {
        self.vars
            .iter()
            .map(|v| format!("`{v}`"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// cond := or [ `if` or `else` cond ]
    fn cond(&mut self) -> Result<Node, String> {
        let then = self.or()?;
        if !self.is_name("if") {
            return Ok(then);
        }
        self.pos += 1;
        let c = self.or()?;
        if !self.is_name("else") {
            return Err(self.err(format!(
                "`if` needs an `else` here: write `a if c else b`; found {}",
                self.describe()
            )));
        }
        self.pos += 1;
        let otherwise = self.cond()?;
        Ok(Node::Cond(Box::new(then), Box::new(c), Box::new(otherwise)))
    }

    fn or(&mut self) -> Result<Node, String> {
        let mut a = self.and()?;
        while self.is_op("||") {
            self.pos += 1;
            a = Node::Binary("||", Box::new(a), Box::new(self.and()?));
        }
        Ok(a)
    }

    fn and(&mut self) -> Result<Node, String> {
        let mut a = self.cmp()?;
        while self.is_op("&&") {
            self.pos += 1;
            a = Node::Binary("&&", Box::new(a), Box::new(self.cmp()?));
        }
        Ok(a)
    }

    fn comparison(&self) -> Option<&'static str> {
        match self.peek() {
            Tok::Op(o) if matches!(*o, "<" | "<=" | ">" | ">=" | "==" | "!=") => Some(o),
            _ => None,
        }
    }

    fn cmp(&mut self) -> Result<Node, String> {
        let a = self.add()?;
        let Some(op) = self.comparison() else {
            return Ok(a);
        };
        self.pos += 1;
        let b = self.add()?;
        if self.comparison().is_some() {
            return Err(self.err(
                "chained comparisons such as 0 < x < 1 are ambiguous here (they would compare the 1/0 of the first with the third); write 0 < x && x < 1",
            ));
        }
        Ok(Node::Binary(op, Box::new(a), Box::new(b)))
    }

    fn add(&mut self) -> Result<Node, String> {
        let mut a = self.mul()?;
        while let Tok::Op(op @ ("+" | "-")) = self.peek() {
            let op = *op;
            self.pos += 1;
            a = Node::Binary(op, Box::new(a), Box::new(self.mul()?));
        }
        Ok(a)
    }

    fn mul(&mut self) -> Result<Node, String> {
        let mut a = self.unary()?.0;
        while let Tok::Op(op @ ("*" | "/")) = self.peek() {
            let op = *op;
            self.pos += 1;
            a = Node::Binary(op, Box::new(a), Box::new(self.unary()?.0));
        }
        Ok(a)
    }

    /// unary := (`-` | `+` | `!`) unary | power. Also returns whether the operand is a power.
    fn unary(&mut self) -> Result<(Node, bool), String> {
        if let Tok::Op(op @ ("-" | "+" | "!")) = self.peek() {
            let (op, col) = (*op, self.col());
            self.pos += 1;
            let (a, is_power) = self.unary()?;
            if is_power {
                let sign = match op {
                    "-" => "a minus sign",
                    "+" => "a plus sign",
                    _ => "a `!`",
                };
                return Err(at(
                    self.source,
                    col,
                    format!(
                        "{sign} in front of a power is ambiguous here (is -x^2 the negative of x², or (−x)²?); write -(x^2) for the negative of the power, or (-x)^2"
                    ),
                ));
            }
            return Ok((Node::Unary(op, Box::new(a)), false));
        }
        self.power()
    }

    /// power := primary [ `^` (`-` | `+`)* primary ]
    fn power(&mut self) -> Result<(Node, bool), String> {
        let base = self.primary()?;
        if !self.is_op("^") {
            return Ok((base, false));
        }
        self.pos += 1;
        let mut signs = Vec::new();
        while let Tok::Op(op @ ("-" | "+")) = self.peek() {
            signs.push(*op);
            self.pos += 1;
        }
        let mut exponent = self.primary()?;
        for op in signs.into_iter().rev() {
            exponent = Node::Unary(op, Box::new(exponent));
        }
        if self.is_op("^") {
            return Err(self.err(
                "chained powers a^b^c are ambiguous here (read as (a^b)^c by some tools, a^(b^c) by others); write (a^b)^c or a^(b^c)",
            ));
        }
        Ok((Node::Binary("^", Box::new(base), Box::new(exponent)), true))
    }

    fn describe(&self) -> String {
        match self.peek() {
            Tok::Num(n) => format!("the number `{n}`"),
            Tok::Name(n) => format!("`{n}`"),
            Tok::Op(o) => format!("`{o}`"),
            Tok::Open => "`(`".into(),
            Tok::Close => "`)`".into(),
            Tok::Comma => "`,`".into(),
            Tok::End => "the end of the expression".into(),
        }
    }

    fn primary(&mut self) -> Result<Node, String> {
        let col = self.col();
        match self.peek().clone() {
            Tok::Num(n) => {
                self.pos += 1;
                Ok(Node::Leaf(n))
            }
            Tok::Open => {
                self.pos += 1;
                let inner = self.cond()?;
                if *self.peek() != Tok::Close {
                    return Err(self.err(format!("expected `)` to close the `(` of column {col}; found {}", self.describe())));
                }
                self.pos += 1;
                // a parenthesised power is an operand of its own: -(x^2) is fine
                Ok(Node::Group(Box::new(inner)))
            }
            Tok::Name(name) if name == "if" || name == "else" => Err(self.err(format!(
                "`{name}` needs a value before it here: the conditional is written `a if c else b`"
            ))),
            Tok::Name(name) if self.vars.contains(&name.as_str()) || CONSTANTS.contains(&name.as_str()) => {
                self.pos += 1;
                Ok(Node::Leaf(name))
            }
            Tok::Name(name) if FUNCTIONS.contains(&name.as_str()) || BINARY_FUNCTIONS.contains(&name.as_str()) => {
                let arity = if FUNCTIONS.contains(&name.as_str()) { 1 } else { 2 };
                let usage = if arity == 1 {
                    format!("{name}(x)")
                } else {
                    format!("{name}(a, b)")
                };
                self.pos += 1;
                if *self.peek() != Tok::Open {
                    return Err(self.err(format!("the function `{name}` takes its argument in parentheses: {usage}")));
                }
                self.pos += 1;
                let mut args = vec![self.cond()?];
                while *self.peek() == Tok::Comma && args.len() < arity {
                    self.pos += 1;
                    args.push(self.cond()?);
                }
                if *self.peek() == Tok::Comma || (args.len() < arity && *self.peek() == Tok::Close) {
                    return Err(self.err(format!(
                        "`{name}` takes {arity} argument{}: {usage}",
                        if arity == 1 { "" } else { "s" }
                    )));
                }
                if *self.peek() != Tok::Close {
                    return Err(self.err(format!("expected `)` to close `{name}(`; found {}", self.describe())));
                }
                self.pos += 1;
                Ok(Node::Call(name, args))
            }
            Tok::Name(name) => Err(at(
                self.source,
                col,
                format!(
                    "unknown variable `{name}`; the variables here are {}; the functions are {}, {}; the constants are {}",
                    self.variables(),
                    FUNCTIONS.join(", "),
                    BINARY_FUNCTIONS.map(|f| format!("{f}(a, b)")).join(", "),
                    CONSTANTS.join(", ")
                ),
            )),
            _ => Err(self.err(format!("expected {OPERAND} here; found {}", self.describe()))),
        }
    }

    fn parse(mut self) -> Result<Node, String> {
        let node = self.cond()?;
        match self.peek() {
            Tok::End => Ok(node),
            Tok::Close => Err(self.err("this `)` closes no `(`")),
            Tok::Name(n) if n == "else" => {
                Err(self.err("`else` without `if`: the conditional is written `a if c else b`"))
            }
            Tok::Comma => Err(self.err("a `,` separates the arguments of min(a, b), max(a, b) and atan2(y, x) only")),
            _ => Err(self.err(format!(
                "expected an operator (+ - * / ^, a comparison, && or ||) before {}",
                self.describe()
            ))),
        }
    }
}

/// A compiled scalar expression over a declared list of variables.
#[derive(Clone, Debug)]
pub struct Expr {
    source: String,
    code: Code,
    /// The variables it reads.
    used: Vec<String>,
}

impl Expr {
    /// Compiles `source`; every variable must be one of `allowed_vars`. An error names the
    /// column, shows the source with a caret under it and says what is valid there.
    pub fn parse(source: &str, allowed_vars: &[&str]) -> Result<Expr, String> {
        if source.trim().is_empty() {
            return Err(format!("the expression is empty; write {OPERAND}"));
        }
        let toks = tokenize(source)?;
        let tree = Parser {
            source,
            toks,
            pos: 0,
            vars: allowed_vars,
        }
        .parse()?;
        let mut used = Vec::new();
        let code = tree.compile(allowed_vars, &mut used)?;
        Ok(Expr {
            source: source.to_string(),
            code,
            used,
        })
    }

    /// The value at `values` (in the order of the declared variables).
    pub fn eval(&self, values: &[f64]) -> f64 {
        self.code.eval(values)
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

    fn eval(source: &str, x: f64) -> f64 {
        Expr::parse(source, &["x"])
            .unwrap_or_else(|e| panic!("{source}: {e}"))
            .eval(&[x])
    }

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
        assert_eq!(eval("1.5e-3*x + 2E2", 2.0), 3e-3 + 200.0);
        assert_eq!(eval("-1.0989010989010988e-2", 0.0), -1.0989010989010988e-2);
        // a minus before a power is rejected, not silently read as (−x)²
        for bad in ["-x^2", "2*-x^2", "-(x+1)^2", "exp(-x^2)", "- 2 ^ 2", "-sin(x)^2"] {
            assert!(Expr::parse(bad, &["x"]).unwrap_err().contains("minus"), "{bad}");
        }
        assert_eq!(eval("-(x^2)", 3.0), -9.0);
        assert_eq!(eval("(-x)^2", 3.0), 9.0);
        assert!(Expr::parse("2^3^2", &["x"]).unwrap_err().contains("chained"));
        assert_eq!(eval("2^(3^2)", 0.0), 512.0);
        assert_eq!(eval("(2^3)^2 + x^2*x^2", 1.0), 65.0);
        assert_eq!(
            Expr::parse("exp(x^2) + y^2", &["x", "y"]).unwrap().eval(&[0.0, 2.0]),
            5.0
        );
        assert_eq!(eval("x-2^2", 3.0), -1.0);
        assert_eq!(eval("x^-2", 2.0), 0.25);
        assert_eq!(eval("exp(-2*x)", 0.0), 1.0);
        assert_eq!(eval("sin(x)^2", 0.5), 0.5f64.sin().powi(2));
    }

    #[test]
    fn arithmetic_is_left_associative() {
        // + and - bind alike, left to right (exmex, the evaluator before issue 19, did not)
        assert_eq!(eval("1 - 2 + 3", 0.0), 2.0);
        assert_eq!(eval("8 / 4 * 2", 0.0), 4.0);
        assert_eq!(eval("8 / 4 / 2", 0.0), 1.0);
        assert_eq!(eval("1 - x - 1", 5.0), -5.0);
        // nested binary functions
        assert_eq!(eval("min(1, max(x, 3))", 2.0), 1.0);
        assert_eq!(eval("max(min(1, 2), min(3, x))", 4.0), 3.0);
        assert_eq!(eval("atan2(1, min(1, x))*4", 1.0), std::f64::consts::PI);
    }

    #[test]
    fn comparisons_logic_and_conditionals() {
        for (source, x, want) in [
            ("x > 0.5", 0.7, 1.0),
            ("x > 0.5", 0.5, 0.0),
            ("x >= 0.5", 0.5, 1.0),
            ("x < 0.5", 0.2, 1.0),
            ("x <= 0.5", 0.6, 0.0),
            ("x == 2", 2.0, 1.0),
            ("x != 2", 2.0, 0.0),
            ("x > 0 && x < 1", 0.5, 1.0),
            ("x > 0 && x < 1", 1.5, 0.0),
            ("x < 0 || x > 1", 1.5, 1.0),
            ("!(x > 1)", 1.5, 0.0),
            ("!x", 0.0, 1.0),
            ("(x > 0.5) * 2", 0.7, 2.0),
            ("x > 0.5 * 2", 0.7, 0.0),
            ("1 + x > 2", 1.5, 1.0),
            ("x^2 if x > 0 else -x", 3.0, 9.0),
            ("x^2 if x > 0 else -x", -3.0, 3.0),
            ("1 if x < 0 else 2 if x < 1 else 3", -1.0, 1.0),
            ("1 if x < 0 else 2 if x < 1 else 3", 0.5, 2.0),
            ("1 if x < 0 else 2 if x < 1 else 3", 5.0, 3.0),
            ("(1 if x > 0 else 2) + 10", 1.0, 11.0),
            ("10 + 1 if x > 0 else 2", -1.0, 2.0),
            // the branch not taken may be undefined there
            ("ln(x) if x > 0 else 0", -1.0, 0.0),
            ("x > 0 && x < 1 || x > 2", 3.0, 1.0),
            ("x > 0 || x < -1 && x > -2", 5.0, 1.0),
        ] {
            assert_eq!(eval(source, x), want, "{source} at x = {x}");
        }
    }

    #[test]
    fn errors_point_at_the_column() {
        let cases = [
            ("x >> 0.99", 4, "expected"),
            ("x = 1", 3, "`==`"),
            ("x & 1", 3, "`&&`"),
            ("0 < x < 1", 7, "chained comparisons"),
            ("2 * foo", 5, "unknown variable `foo`"),
            ("1 if x > 0", 11, "`else`"),
            ("1 else 2", 3, "`else` without `if`"),
            ("sin x", 5, "in parentheses"),
            ("min(1)", 6, "2 arguments"),
            ("sin(1, 2)", 6, "1 argument"),
            ("(x + 1", 7, "`)`"),
            ("x + 1)", 6, "closes no"),
            ("2 x", 3, "expected an operator"),
            ("x + * 2", 5, "expected a number"),
            ("x % 2", 3, "not part of the language"),
            ("3 * -x^2", 5, "minus"),
            ("x^2^3", 4, "chained powers"),
        ];
        for (source, col, says) in cases {
            let e = Expr::parse(source, &["x"]).unwrap_err();
            assert!(e.starts_with(&format!("column {col}:")), "{source}: {e}");
            assert!(e.contains(says), "{source}: {e}");
            // the caret sits under the column
            let caret = e.lines().last().unwrap();
            assert_eq!(caret.find('^'), Some(4 + col - 1), "{source}:\n{e}");
        }
        assert!(Expr::parse("  ", &["x"]).unwrap_err().contains("empty"));
    }
}
