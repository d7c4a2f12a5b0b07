//! Parsing Radiance's function language into expression trees (`src/common/calexpr.c`'s
//! grammar, `caldefn.c`'s statements):
//!
//! ```text
//! statement  := name '=' E1 ';' | name ':' E1 ';' | name '(' params ')' ('=' | ':') E1 ';' | ';'
//! E1 := E2 { ('+' | '-') E2 }      E2 := E3 { ('*' | '/') E3 }      E3 := E4 [ '^' E3 ]
//! E4 := '-' E5 | '+' E5 | E5       E5 := '(' E1 ')' | number | name | name '(' E1 {',' E1} ')'
//! ```
//!
//! so unary minus binds tighter than `^` (`-2^2` is 4) and `^` groups to the right. Names start
//! with a letter and go on with letters, digits, `_` and `.`; `{ … }` is a comment and may nest.

use crate::error::SourceLocation;
use crate::SceneError;
use std::path::PathBuf;
use std::sync::Arc;

/// A binary operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Operator {
    /// `+`
    Add,
    /// `-`
    Subtract,
    /// `*`
    Multiply,
    /// `/`
    Divide,
    /// `^`
    Power,
}

/// An expression as written.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A number.
    Number(f64),
    /// A name: a variable, a parameter, a channel or (as an argument) a function.
    Name(String),
    /// A call of a function (a definition, a parameter holding one, or the library's).
    Call(String, Vec<Expr>),
    /// Unary minus.
    Negate(Box<Expr>),
    /// A binary operation.
    Binary(Operator, Box<Expr>, Box<Expr>),
}

/// One definition.
#[derive(Clone, Debug)]
pub struct Definition {
    /// The name defined.
    pub name: String,
    /// The parameters of a function; `None` for a variable.
    pub params: Option<Vec<String>>,
    /// Defined with `:` (a constant) rather than `=`.
    pub constant: bool,
    /// The right-hand side.
    pub body: Expr,
    /// Where the definition starts.
    pub location: SourceLocation,
}

/// The definitions of a file's text, in order.
pub fn parse_definitions(text: &str, file: Arc<PathBuf>) -> Result<Vec<Definition>, SceneError> {
    let mut p = Parser::new(text, file, 1);
    let mut out = Vec::new();
    loop {
        p.skip();
        match p.peek() {
            None => return Ok(out),
            Some(b';') => p.bump(),
            Some(_) => {
                out.push(p.definition()?);
                p.skip();
                match p.peek() {
                    None => return Ok(out),
                    Some(b';') => p.bump(),
                    Some(c) => return Err(p.error(format!("';' expected, found '{}'", c as char))),
                }
            }
        }
    }
}

/// One expression (a modifier's string argument), which must use all of `text`; `location` is
/// where the text was written.
pub fn parse_expression(text: &str, location: &SourceLocation) -> Result<Expr, SceneError> {
    let mut p = Parser::new(text, location.file.clone(), location.line);
    let e = p.e1()?;
    p.skip();
    if let Some(c) = p.peek() {
        return Err(SceneError::at(
            location.clone(),
            format!(
                "expression \"{text}\": unexpected '{}' after its end",
                c as char
            ),
        ));
    }
    Ok(e)
}

struct Parser<'a> {
    text: &'a [u8],
    pos: usize,
    line: u32,
    line_start: usize,
    file: Arc<PathBuf>,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str, file: Arc<PathBuf>, line: u32) -> Parser<'a> {
        Parser {
            text: text.as_bytes(),
            pos: 0,
            line,
            line_start: 0,
            file,
        }
    }

    fn location(&self) -> SourceLocation {
        SourceLocation {
            file: self.file.clone(),
            line: self.line,
            column: (self.pos - self.line_start + 1) as u32,
        }
    }

    fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::at(self.location(), message)
    }

    fn peek(&self) -> Option<u8> {
        self.text.get(self.pos).copied()
    }

    fn bump(&mut self) {
        if self.peek() == Some(b'\n') {
            self.line += 1;
            self.line_start = self.pos + 1;
        }
        self.pos += 1;
    }

    /// Skips white space and (nested) comments.
    fn skip(&mut self) {
        let mut depth = 0usize;
        while let Some(c) = self.peek() {
            match c {
                b'{' => depth += 1,
                b'}' if depth > 0 => depth -= 1,
                _ if depth > 0 || c.is_ascii_whitespace() => {}
                _ => return,
            }
            self.bump();
        }
    }

    /// The next non-space byte, consumed if it is `c`.
    fn eat(&mut self, c: u8) -> bool {
        self.skip();
        if self.peek() == Some(c) {
            self.bump();
            true
        } else {
            false
        }
    }

    fn expect(&mut self, c: u8) -> Result<(), SceneError> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(self.found(&format!("'{}'", c as char)))
        }
    }

    fn found(&self, expected: &str) -> SceneError {
        match self.peek() {
            None => self.error(format!("{expected} expected at the end of the text")),
            Some(c) => self.error(format!("{expected} expected, found '{}'", c as char)),
        }
    }

    fn name(&mut self) -> Result<String, SceneError> {
        self.skip();
        if !self.peek().is_some_and(|c| c.is_ascii_alphabetic()) {
            return Err(self.found("a name"));
        }
        let start = self.pos;
        while self
            .peek()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_' || c == b'.')
        {
            self.bump();
        }
        if self.peek() == Some(b'`') {
            return Err(self.error("context names (`) are not supported"));
        }
        Ok(String::from_utf8_lossy(&self.text[start..self.pos]).into_owned())
    }

    fn definition(&mut self) -> Result<Definition, SceneError> {
        self.skip();
        let location = self.location();
        let name = self.name()?;
        let params = if self.eat(b'(') {
            let mut params = vec![self.name()?];
            while self.eat(b',') {
                params.push(self.name()?);
            }
            self.expect(b')')?;
            Some(params)
        } else {
            None
        };
        self.skip();
        let constant = match self.peek() {
            Some(b'=') => false,
            Some(b':') => true,
            _ => return Err(self.found("'=' or ':'")),
        };
        self.bump();
        let body = self.e1()?;
        Ok(Definition {
            name,
            params,
            constant,
            body,
            location,
        })
    }

    fn e1(&mut self) -> Result<Expr, SceneError> {
        let mut left = self.e2()?;
        loop {
            let op = if self.eat(b'+') {
                Operator::Add
            } else if self.eat(b'-') {
                Operator::Subtract
            } else {
                return Ok(left);
            };
            left = Expr::Binary(op, Box::new(left), Box::new(self.e2()?));
        }
    }

    fn e2(&mut self) -> Result<Expr, SceneError> {
        let mut left = self.e3()?;
        loop {
            let op = if self.eat(b'*') {
                Operator::Multiply
            } else if self.eat(b'/') {
                Operator::Divide
            } else {
                return Ok(left);
            };
            left = Expr::Binary(op, Box::new(left), Box::new(self.e3()?));
        }
    }

    fn e3(&mut self) -> Result<Expr, SceneError> {
        let base = self.e4()?;
        if self.eat(b'^') {
            Ok(Expr::Binary(
                Operator::Power,
                Box::new(base),
                Box::new(self.e3()?),
            ))
        } else {
            Ok(base)
        }
    }

    fn e4(&mut self) -> Result<Expr, SceneError> {
        if self.eat(b'-') {
            return Ok(match self.e5()? {
                Expr::Number(v) => Expr::Number(-v),
                Expr::Negate(e) => *e,
                e => Expr::Negate(Box::new(e)),
            });
        }
        self.eat(b'+');
        self.e5()
    }

    fn e5(&mut self) -> Result<Expr, SceneError> {
        self.skip();
        match self.peek() {
            Some(b'(') => {
                self.bump();
                let e = self.e1()?;
                self.expect(b')')?;
                Ok(e)
            }
            Some(c) if c.is_ascii_alphabetic() => {
                let name = self.name()?;
                if self.eat(b'(') {
                    let mut args = vec![self.e1()?];
                    while self.eat(b',') {
                        args.push(self.e1()?);
                    }
                    self.expect(b')')?;
                    Ok(Expr::Call(name, args))
                } else {
                    Ok(Expr::Name(name))
                }
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => self.number(),
            _ => Err(self.found("an expression")),
        }
    }

    /// A decimal number: digits, an optional fraction and exponent.
    fn number(&mut self) -> Result<Expr, SceneError> {
        let start = self.pos;
        let digits = |p: &mut Parser| {
            while p.peek().is_some_and(|c| c.is_ascii_digit()) {
                p.bump();
            }
        };
        digits(self);
        if self.peek() == Some(b'.') {
            self.bump();
            digits(self);
        }
        if matches!(self.peek(), Some(b'e' | b'E')) {
            let mark = self.pos;
            self.bump();
            if matches!(self.peek(), Some(b'+' | b'-')) {
                self.bump();
            }
            if self.peek().is_some_and(|c| c.is_ascii_digit()) {
                digits(self);
            } else {
                self.pos = mark;
            }
        }
        let s = String::from_utf8_lossy(&self.text[start..self.pos]);
        s.parse::<f64>()
            .map(Expr::Number)
            .map_err(|_| self.error(format!("\"{s}\" is not a number")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn expr(s: &str) -> Expr {
        parse_expression(s, &SourceLocation::start_of(std::path::Path::new("t"))).unwrap()
    }

    #[test]
    fn precedence_is_radiance_s() {
        use Expr::*;
        // Unary minus binds tighter than ^; ^ groups to the right.
        assert_eq!(
            expr("-x^2"),
            Binary(
                Operator::Power,
                Box::new(Negate(Box::new(Name("x".into())))),
                Box::new(Number(2.0))
            )
        );
        assert_eq!(
            expr("2^3^2"),
            Binary(
                Operator::Power,
                Box::new(Number(2.0)),
                Box::new(Binary(
                    Operator::Power,
                    Box::new(Number(3.0)),
                    Box::new(Number(2.0))
                ))
            )
        );
        assert!(
            matches!(expr("a-b-c"), Binary(Operator::Subtract, l, _) if matches!(*l, Binary(Operator::Subtract, _, _)))
        );
        assert!(
            matches!(expr("a+b*c"), Binary(Operator::Add, _, r) if matches!(*r, Binary(Operator::Multiply, _, _)))
        );
        assert_eq!(expr("1.5e-3"), Number(1.5e-3));
        assert_eq!(expr(".5"), Number(0.5));
    }

    #[test]
    fn definitions_comments_and_errors() {
        let f = Arc::new(PathBuf::from("f.cal"));
        let defs = parse_definitions(
            "{ a {nested} comment }\nA1 = arg(1);\nsq(x) : x*x;\n;\nmod(n,d) : n - floor(n/d)*d",
            f.clone(),
        )
        .unwrap();
        assert_eq!(defs.len(), 3);
        assert_eq!(defs[1].params.as_deref(), Some(&["x".to_string()][..]));
        assert!(defs[1].constant && !defs[0].constant);
        assert_eq!(defs[2].location.line, 5);
        let e = parse_definitions("a = 1;\nb = (2 + ;", f.clone()).unwrap_err();
        assert!(e.to_string().contains("f.cal:2:"), "{e}");
        let e = parse_definitions("a = 1 b = 2;", f).unwrap_err();
        assert!(e.to_string().contains("';' expected"), "{e}");
    }
}
