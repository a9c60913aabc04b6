//! ISO 10303-21 ("Part 21", the STEP clear-text encoding) parser.
//!
//! Reads the exchange structure `ISO-10303-21; HEADER; … ENDSEC; DATA; …
//! ENDSEC; END-ISO-10303-21;` into entity instances: `#12 = NAME(…);`
//! (simple) and `#12 = (A(…) B(…));` (complex, ISO 10303-21 §11.2.5.3),
//! with the parameter tokens of §6.4: integers, reals (`1.`, `-2.5E-3`),
//! strings `'…'` (with `''` for a quote), enumerations `.T.`, entity names
//! `#7`, lists `(…)`, typed parameters `NAME(…)`, binaries `"…"`, unset `$`
//! and derived `*`. Comments `/* … */` are skipped anywhere. Nesting is
//! limited to [`MAX_DEPTH`] so that hostile input cannot exhaust the stack.

use std::collections::HashMap;

/// Deepest list nesting accepted.
pub const MAX_DEPTH: usize = 64;

/// One parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// `$`: not given.
    Unset,
    /// `*`: derived.
    Derived,
    /// An integer.
    Integer(i64),
    /// A real.
    Real(f64),
    /// A string (quotes removed, `''` made one quote; control directives
    /// such as `\X\` are kept as written).
    Text(String),
    /// An enumeration `.NAME.` (without the dots).
    Enum(String),
    /// An entity instance name `#id`.
    Ref(u64),
    /// A list `( … )`.
    List(Vec<Value>),
    /// A typed parameter `NAME(value)`.
    Typed(String, Box<Value>),
    /// A binary `"…"`.
    Binary(String),
}

impl Value {
    /// The number of an integer or real (typed parameters unwrapped).
    pub fn number(&self) -> Option<f64> {
        match self {
            Value::Integer(i) => Some(*i as f64),
            Value::Real(x) => Some(*x),
            Value::Typed(_, v) => v.number(),
            _ => None,
        }
    }
}

/// One entity instance: its name and its partial entities (one for a
/// simple instance, several for a complex one), each a type name in upper
/// case and its parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// `#id`.
    pub id: u64,
    /// `(TYPE, parameters)` in file order.
    pub parts: Vec<(String, Vec<Value>)>,
    /// 1-based line where the instance starts.
    pub line: usize,
}

impl Instance {
    /// The parameters of the partial entity `name`, if the instance has it.
    pub fn part(&self, name: &str) -> Option<&[Value]> {
        self.parts
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    /// The type name of a simple instance, the first part's of a complex one.
    pub fn type_name(&self) -> &str {
        self.parts.first().map_or("", |(n, _)| n.as_str())
    }

    /// Whether the instance has a partial entity `name`.
    pub fn is(&self, name: &str) -> bool {
        self.parts.iter().any(|(n, _)| n == name)
    }
}

/// The DATA section: instances by id.
#[derive(Clone, Debug, Default)]
pub struct Exchange {
    /// Every instance.
    pub instances: HashMap<u64, Instance>,
    /// Ids in file order.
    pub order: Vec<u64>,
}

/// A syntax error: 1-based line and message.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntaxError {
    /// Line.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

struct Lexer<'a> {
    s: &'a [u8],
    pos: usize,
    line: usize,
}

type Res<T> = Result<T, SyntaxError>;

impl<'a> Lexer<'a> {
    fn err<T>(&self, message: impl Into<String>) -> Res<T> {
        Err(SyntaxError {
            line: self.line,
            message: message.into(),
        })
    }

    /// Skips white space and comments.
    fn skip(&mut self) -> Res<()> {
        loop {
            match self.s.get(self.pos) {
                Some(b'\n') => {
                    self.line += 1;
                    self.pos += 1;
                }
                Some(c) if c.is_ascii_whitespace() => self.pos += 1,
                Some(b'/') if self.s.get(self.pos + 1) == Some(&b'*') => {
                    let start = self.line;
                    self.pos += 2;
                    loop {
                        match self.s.get(self.pos) {
                            None => {
                                return Err(SyntaxError {
                                    line: start,
                                    message: "comment `/*` is never closed".into(),
                                });
                            }
                            Some(b'*') if self.s.get(self.pos + 1) == Some(&b'/') => {
                                self.pos += 2;
                                break;
                            }
                            Some(b'\n') => {
                                self.line += 1;
                                self.pos += 1;
                            }
                            _ => self.pos += 1,
                        }
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    fn peek(&mut self) -> Res<Option<u8>> {
        self.skip()?;
        Ok(self.s.get(self.pos).copied())
    }

    fn expect_byte(&mut self, c: u8) -> Res<()> {
        match self.peek()? {
            Some(x) if x == c => {
                self.pos += 1;
                Ok(())
            }
            Some(x) => self.err(format!("expected `{}`, found `{}`", c as char, x as char)),
            None => self.err(format!(
                "expected `{}`, found the end of the file",
                c as char
            )),
        }
    }

    /// A keyword (`[A-Za-z_][A-Za-z0-9_-]*`, upper-cased); `!` user keywords too.
    fn keyword(&mut self) -> Res<String> {
        self.skip()?;
        let start = self.pos;
        if self.s.get(self.pos) == Some(&b'!') {
            self.pos += 1;
        }
        while let Some(&c) = self.s.get(self.pos) {
            if c.is_ascii_alphanumeric() || c == b'_' || c == b'-' {
                self.pos += 1;
            } else {
                break;
            }
        }
        if self.pos == start {
            return self.err("expected a keyword");
        }
        Ok(String::from_utf8_lossy(&self.s[start..self.pos]).to_ascii_uppercase())
    }

    fn digits(&mut self) {
        while self.s.get(self.pos).is_some_and(u8::is_ascii_digit) {
            self.pos += 1;
        }
    }

    fn value(&mut self, depth: usize) -> Res<Value> {
        if depth > MAX_DEPTH {
            return self.err(format!("lists nest deeper than {MAX_DEPTH}"));
        }
        let Some(c) = self.peek()? else {
            return self.err("expected a parameter, found the end of the file");
        };
        match c {
            b'$' => {
                self.pos += 1;
                Ok(Value::Unset)
            }
            b'*' => {
                self.pos += 1;
                Ok(Value::Derived)
            }
            b'(' => Ok(Value::List(self.list(depth + 1)?)),
            b'#' => {
                self.pos += 1;
                let start = self.pos;
                self.digits();
                std::str::from_utf8(&self.s[start..self.pos])
                    .ok()
                    .and_then(|t| t.parse().ok())
                    .map(Value::Ref)
                    .map_or_else(|| self.err("expected digits after `#`"), Ok)
            }
            b'\'' => {
                self.pos += 1;
                let mut out = Vec::new();
                loop {
                    match self.s.get(self.pos) {
                        None => return self.err("string is never closed"),
                        Some(b'\'') if self.s.get(self.pos + 1) == Some(&b'\'') => {
                            out.push(b'\'');
                            self.pos += 2;
                        }
                        Some(b'\'') => {
                            self.pos += 1;
                            break;
                        }
                        Some(&c) => {
                            if c == b'\n' {
                                self.line += 1;
                            }
                            out.push(c);
                            self.pos += 1;
                        }
                    }
                }
                Ok(Value::Text(String::from_utf8_lossy(&out).into_owned()))
            }
            b'"' => {
                self.pos += 1;
                let start = self.pos;
                while self.s.get(self.pos).is_some_and(|&c| c != b'"') {
                    self.pos += 1;
                }
                if self.pos >= self.s.len() {
                    return self.err("binary is never closed");
                }
                let b = String::from_utf8_lossy(&self.s[start..self.pos]).into_owned();
                self.pos += 1;
                Ok(Value::Binary(b))
            }
            b'.' if self
                .s
                .get(self.pos + 1)
                .is_some_and(u8::is_ascii_alphabetic) =>
            {
                self.pos += 1;
                let start = self.pos;
                while self
                    .s
                    .get(self.pos)
                    .is_some_and(|&c| c.is_ascii_alphanumeric() || c == b'_')
                {
                    self.pos += 1;
                }
                let name = String::from_utf8_lossy(&self.s[start..self.pos]).to_ascii_uppercase();
                if self.s.get(self.pos) != Some(&b'.') {
                    return self.err(format!("enumeration `.{name}` has no closing `.`"));
                }
                self.pos += 1;
                Ok(Value::Enum(name))
            }
            b'+' | b'-' | b'.' | b'0'..=b'9' => self.number(),
            c if c.is_ascii_alphabetic() || c == b'!' => {
                let name = self.keyword()?;
                self.expect_byte(b'(')?;
                let v = self.value(depth + 1)?;
                self.expect_byte(b')')?;
                Ok(Value::Typed(name, Box::new(v)))
            }
            c => self.err(format!("unexpected `{}` in a parameter list", c as char)),
        }
    }

    fn number(&mut self) -> Res<Value> {
        let start = self.pos;
        if matches!(self.s.get(self.pos), Some(b'+' | b'-')) {
            self.pos += 1;
        }
        self.digits();
        let mut real = false;
        if self.s.get(self.pos) == Some(&b'.') {
            real = true;
            self.pos += 1;
            self.digits();
        }
        if matches!(self.s.get(self.pos), Some(b'E' | b'e')) {
            real = true;
            self.pos += 1;
            if matches!(self.s.get(self.pos), Some(b'+' | b'-')) {
                self.pos += 1;
            }
            self.digits();
        }
        let text = std::str::from_utf8(&self.s[start..self.pos]).unwrap_or("");
        if real {
            match text.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(Value::Real(x)),
                _ => self.err(format!("`{text}` is not a finite real number")),
            }
        } else {
            match text.parse::<i64>() {
                Ok(i) => Ok(Value::Integer(i)),
                Err(_) => self.err(format!("`{text}` is not an integer")),
            }
        }
    }

    /// `( v, v, … )` (possibly empty).
    fn list(&mut self, depth: usize) -> Res<Vec<Value>> {
        self.expect_byte(b'(')?;
        let mut out = Vec::new();
        if self.peek()? == Some(b')') {
            self.pos += 1;
            return Ok(out);
        }
        loop {
            out.push(self.value(depth)?);
            match self.peek()? {
                Some(b',') => self.pos += 1,
                Some(b')') => {
                    self.pos += 1;
                    return Ok(out);
                }
                Some(c) => {
                    return self.err(format!("expected `,` or `)`, found `{}`", c as char));
                }
                None => return self.err("a list is never closed"),
            }
        }
    }

    /// Skips to just after the next `;` outside strings and comments.
    fn skip_statement(&mut self) -> Res<()> {
        loop {
            match self.peek()? {
                None => return self.err("statement has no closing `;`"),
                Some(b';') => {
                    self.pos += 1;
                    return Ok(());
                }
                Some(b'\'' | b'"' | b'(') => {
                    self.value(0)?;
                }
                Some(_) => self.pos += 1,
            }
        }
    }
}

/// Parses a Part 21 file (its DATA sections).
pub fn parse(bytes: &[u8]) -> Res<Exchange> {
    let mut lx = Lexer {
        s: bytes,
        pos: 0,
        line: 1,
    };
    let magic = lx.keyword()?;
    if magic != "ISO-10303-21" {
        return lx.err(format!(
            "not a STEP file: it starts with `{magic}`, not `ISO-10303-21;`"
        ));
    }
    lx.expect_byte(b';')?;
    let mut ex = Exchange::default();
    loop {
        let Some(c) = lx.peek()? else {
            return lx.err("the file ends without `END-ISO-10303-21;`");
        };
        if c == b'#' {
            return lx.err("an entity instance outside a DATA section");
        }
        let kw = lx.keyword()?;
        match kw.as_str() {
            "END-ISO-10303-21" => return Ok(ex),
            "HEADER" => {
                lx.expect_byte(b';')?;
                loop {
                    let k = lx.keyword()?;
                    if k == "ENDSEC" {
                        lx.expect_byte(b';')?;
                        break;
                    }
                    lx.skip_statement()?;
                }
            }
            "DATA" => {
                if lx.peek()? == Some(b'(') {
                    lx.list(1)?;
                }
                lx.expect_byte(b';')?;
                data_section(&mut lx, &mut ex)?;
            }
            other => return lx.err(format!("unexpected `{other}` between sections")),
        }
    }
}

fn data_section(lx: &mut Lexer<'_>, ex: &mut Exchange) -> Res<()> {
    loop {
        match lx.peek()? {
            Some(b'#') => {}
            Some(_) => {
                let k = lx.keyword()?;
                if k == "ENDSEC" {
                    return lx.expect_byte(b';');
                }
                return lx.err(format!("expected `#id =` or `ENDSEC`, found `{k}`"));
            }
            None => return lx.err("the DATA section has no `ENDSEC;`"),
        }
        let line = lx.line;
        let Value::Ref(id) = lx.value(0)? else {
            return lx.err("expected an entity instance name `#id`");
        };
        lx.expect_byte(b'=')?;
        let mut parts = Vec::new();
        if lx.peek()? == Some(b'(') {
            lx.pos += 1;
            while lx.peek()? != Some(b')') {
                let name = lx.keyword()?;
                let params = lx.list(1)?;
                parts.push((name, params));
            }
            lx.pos += 1;
            if parts.is_empty() {
                return lx.err(format!("#{id}: a complex entity with no partial entity"));
            }
        } else {
            let name = lx.keyword()?;
            let params = lx.list(1)?;
            parts.push((name, params));
        }
        lx.expect_byte(b';')?;
        if ex
            .instances
            .insert(id, Instance { id, parts, line })
            .is_some()
        {
            return Err(SyntaxError {
                line,
                message: format!("#{id} is defined twice"),
            });
        }
        ex.order.push(id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn p21_parses_simple_complex_and_typed_instances() {
        let text = "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('a;b'),'2;1');\nENDSEC;\n\
            DATA;\n/* a comment; with ( */\n#1=CARTESIAN_POINT('it''s',(1.,-2.5E-1,3));\n\
            #2 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n\
            #3=MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#2);\n#4=X($,\"0FF\",());\nENDSEC;\n\
            END-ISO-10303-21;\n";
        let ex = parse(text.as_bytes()).unwrap();
        assert_eq!(ex.order, vec![1, 2, 3, 4]);
        let p = &ex.instances[&1];
        assert_eq!(p.line, 7);
        assert_eq!(p.type_name(), "CARTESIAN_POINT");
        assert_eq!(
            p.parts[0].1,
            vec![
                Value::Text("it's".into()),
                Value::List(vec![
                    Value::Real(1.0),
                    Value::Real(-0.25),
                    Value::Integer(3)
                ])
            ]
        );
        let u = &ex.instances[&2];
        assert!(u.is("LENGTH_UNIT") && u.is("SI_UNIT"));
        assert_eq!(
            u.part("SI_UNIT").unwrap(),
            &[Value::Enum("MILLI".into()), Value::Enum("METRE".into())]
        );
        assert_eq!(u.part("NAMED_UNIT").unwrap(), &[Value::Derived]);
        assert_eq!(ex.instances[&3].parts[0].1[0].number(), Some(25.4));
        assert_eq!(
            ex.instances[&4].parts[0].1,
            vec![
                Value::Unset,
                Value::Binary("0FF".into()),
                Value::List(vec![])
            ]
        );
    }

    #[test]
    fn p21_errors_name_the_line() {
        let bad = |t: &str| parse(t.as_bytes()).unwrap_err();
        assert!(bad("HELLO;").message.contains("not a STEP file"));
        let e = bad("ISO-10303-21;\nDATA;\n#1=A(1,2;\nENDSEC;END-ISO-10303-21;");
        assert_eq!(e.line, 3);
        let e = bad("ISO-10303-21;\nDATA;\n#1=A(1);\n#1=B(2);\nENDSEC;END-ISO-10303-21;");
        assert!(e.message.contains("#1 is defined twice"), "{e:?}");
        let deep = format!(
            "ISO-10303-21;DATA;#1=A({}{});ENDSEC;END-ISO-10303-21;",
            "(".repeat(10_000),
            ")".repeat(10_000)
        );
        assert!(bad(&deep).message.contains("nest deeper"));
        assert!(
            bad("ISO-10303-21;DATA;#1=A(1e999);ENDSEC;END-ISO-10303-21;")
                .message
                .contains("finite")
        );
        assert!(
            bad("ISO-10303-21;DATA;#1=A('x);")
                .message
                .contains("never closed")
        );
    }
}
