//! The subset of Structured Text that declares a process image:
//! `TYPE … END_TYPE` with structures, aliases and arrays of elementary and
//! declared types, and TwinCAT's `pack_mode` attribute (IEC 61131-3 §2.3.3;
//! TwinCAT's pragmas). What lies outside `TYPE` blocks (programs, variable
//! lists) is passed over; inside one, anything canif cannot size is an error.
//!
//! A parser of its own rather than one of crates.io's ST parsers (iecst,
//! iec61131, ironplc-parser): those read programs to the IEC 2013 grammar,
//! while this needs TwinCAT's attribute pragmas on the type they precede,
//! the line of every member, `BIT` members, and nothing of statements.

use crate::error::{Cause, DeclarationError, Place};
use crate::source::Source;
use crate::types::Elementary;

/// A type expression as written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TypeExpr {
    Elementary(Elementary),
    /// `STRING(n)`: n characters and the terminating 0.
    String {
        bytes: usize,
    },
    Array {
        low: i64,
        high: i64,
        element: Box<TypeExpr>,
    },
    Named(String),
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MemberDecl {
    pub name: String,
    pub line: usize,
    pub data_type: TypeExpr,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Body {
    Struct(Vec<MemberDecl>),
    Alias(TypeExpr),
}

/// One `name : …` of a `TYPE` block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TypeDecl {
    pub name: String,
    pub place: Place,
    /// `{attribute 'pack_mode' := 'n'}` above it.
    pub pack_mode: Option<u8>,
    pub body: Body,
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Word(String),
    Number(i64),
    Pragma(String),
    Symbol(&'static str),
    Other(char),
}

impl Token {
    fn is_word(&self, word: &str) -> bool {
        matches!(self, Token::Word(w) if w.eq_ignore_ascii_case(word))
    }

    fn text(&self) -> String {
        match self {
            Token::Word(w) => w.clone(),
            Token::Number(n) => n.to_string(),
            Token::Pragma(p) => format!("{{{p}}}"),
            Token::Symbol(s) => s.to_string(),
            Token::Other(c) => c.to_string(),
        }
    }
}

const SYMBOLS: [&str; 10] = [":=", "..", ":", ";", ",", "[", "]", "(", ")", "-"];

fn lex(source: &Source) -> Result<Vec<(Token, usize)>, DeclarationError> {
    let chars: Vec<char> = source.text.chars().collect();
    let mut tokens = Vec::new();
    let mut line = source.first_line;
    let mut at = 0;
    let error = |line, cause| DeclarationError {
        place: Place {
            file: source.file.clone(),
            line,
        },
        cause,
    };
    let starts = |at: usize, text: &str| {
        text.chars()
            .enumerate()
            .all(|(i, c)| chars.get(at + i) == Some(&c))
    };
    while at < chars.len() {
        let c = chars[at];
        if c == '\n' {
            line += 1;
            at += 1;
        } else if c.is_whitespace() {
            at += 1;
        } else if starts(at, "//") {
            while at < chars.len() && chars[at] != '\n' {
                at += 1;
            }
        } else if starts(at, "(*") {
            // TwinCAT nests comments.
            let (opened, mut depth) = (line, 0);
            loop {
                if at >= chars.len() {
                    return Err(error(opened, Cause::Unterminated("a comment `(*`")));
                }
                if starts(at, "(*") {
                    depth += 1;
                    at += 2;
                } else if starts(at, "*)") {
                    depth -= 1;
                    at += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    line += usize::from(chars[at] == '\n');
                    at += 1;
                }
            }
        } else if c == '{' {
            let opened = line;
            let end = (at..chars.len())
                .find(|&i| chars[i] == '}')
                .ok_or_else(|| error(opened, Cause::Unterminated("a pragma `{`")))?;
            let text: String = chars[at + 1..end].iter().collect();
            line += text.matches('\n').count();
            tokens.push((Token::Pragma(text), opened));
            at = end + 1;
        } else if c == '\'' || c == '"' {
            // A string ends on its line; a lone quote (an apostrophe in a
            // file that is no ST) is left to the parser to refuse.
            let end = (at + 1..chars.len())
                .take_while(|&i| chars[i] != '\n')
                .find(|&i| chars[i] == c);
            tokens.push((Token::Other(c), line));
            at = end.map_or(at + 1, |end| end + 1);
        } else if c.is_ascii_alphabetic() || c == '_' {
            let end = (at..chars.len())
                .find(|&i| !(chars[i].is_ascii_alphanumeric() || chars[i] == '_'))
                .unwrap_or(chars.len());
            tokens.push((Token::Word(chars[at..end].iter().collect()), line));
            at = end;
        } else if c.is_ascii_digit() {
            let end = (at..chars.len())
                .find(|&i| !(chars[i].is_ascii_alphanumeric() || matches!(chars[i], '_' | '#')))
                .unwrap_or(chars.len());
            let text: String = chars[at..end].iter().filter(|&&c| c != '_').collect();
            let value = match text.split_once('#') {
                Some((radix, digits)) => radix
                    .parse()
                    .ok()
                    .filter(|r| [2, 8, 16].contains(r))
                    .and_then(|r| i64::from_str_radix(digits, r).ok()),
                None => text.parse().ok(),
            };
            tokens.push(match value {
                Some(n) => (Token::Number(n), line),
                None => (Token::Other(c), line),
            });
            at = end;
        } else if let Some(symbol) = SYMBOLS.iter().find(|s| starts(at, s)) {
            tokens.push((Token::Symbol(symbol), line));
            at += symbol.len();
        } else {
            tokens.push((Token::Other(c), line));
            at += 1;
        }
    }
    Ok(tokens)
}

struct Parser<'a> {
    tokens: Vec<(Token, usize)>,
    at: usize,
    file: &'a str,
    /// Nested `ARRAY … OF` of the type being read.
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.at).map(|t| &t.0)
    }

    fn line(&self) -> usize {
        self.tokens
            .get(self.at)
            .or(self.tokens.last())
            .map_or(1, |t| t.1)
    }

    fn error(&self, cause: Cause) -> DeclarationError {
        DeclarationError {
            place: Place {
                file: self.file.to_string(),
                line: self.line(),
            },
            cause,
        }
    }

    fn expected(&self, expected: &'static str) -> DeclarationError {
        let found = self
            .peek()
            .map_or_else(|| "the end of the file".to_string(), Token::text);
        self.error(Cause::Expected { expected, found })
    }

    fn next(&mut self) -> Option<Token> {
        let token = self.tokens.get(self.at).map(|t| t.0.clone());
        self.at += 1;
        token
    }

    fn eat_word(&mut self, word: &str) -> bool {
        let found = self.peek().is_some_and(|t| t.is_word(word));
        self.at += usize::from(found);
        found
    }

    fn eat(&mut self, symbol: &str) -> bool {
        let found = matches!(self.peek(), Some(Token::Symbol(s)) if *s == symbol);
        self.at += usize::from(found);
        found
    }

    fn expect(&mut self, symbol: &'static str) -> Result<(), DeclarationError> {
        match self.eat(symbol) {
            true => Ok(()),
            false => Err(self.expected(symbol)),
        }
    }

    fn name(&mut self, what: &'static str) -> Result<String, DeclarationError> {
        match self.peek() {
            Some(Token::Word(w)) => {
                let w = w.clone();
                self.at += 1;
                Ok(w)
            }
            _ => Err(self.expected(what)),
        }
    }

    /// Pragmas in front of a declaration: the pack mode they set.
    fn pragmas(&mut self) -> Result<Option<u8>, DeclarationError> {
        let mut pack_mode = None;
        while let Some(Token::Pragma(text)) = self.peek() {
            if let Some(value) = pack_mode_of(text) {
                pack_mode = Some(
                    value
                        .parse()
                        .ok()
                        .filter(|v| [0, 1, 2, 4, 8].contains(v))
                        .ok_or_else(|| self.error(Cause::PackMode(value.to_string())))?,
                );
            }
            self.at += 1;
        }
        Ok(pack_mode)
    }

    fn type_block(&mut self, out: &mut Vec<TypeDecl>) -> Result<(), DeclarationError> {
        let mut pack_mode = None;
        loop {
            pack_mode = self.pragmas()?.or(pack_mode);
            if self.eat_word("END_TYPE") {
                return Ok(());
            }
            let line = self.line();
            let name = self.name("a type name or END_TYPE")?;
            if self.peek().is_some_and(|t| t.is_word("EXTENDS")) {
                return Err(self.error(Cause::Unsized("a structure that EXTENDS another")));
            }
            self.expect(":")?;
            let body = if self.eat_word("STRUCT") {
                let mut members = Vec::new();
                while !self.eat_word("END_STRUCT") {
                    self.member(&mut members)?;
                }
                Body::Struct(members)
            } else if self.peek().is_some_and(|t| t.is_word("UNION")) {
                return Err(self.error(Cause::Unsized("a UNION")));
            } else if self.eat("(") {
                // An enumeration: its base type after the list, INT without one.
                while !self.eat(")") {
                    if self.next().is_none() {
                        return Err(self.expected(")"));
                    }
                }
                match self.peek() {
                    Some(Token::Word(_)) => Body::Alias(self.type_expr()?),
                    _ => Body::Alias(TypeExpr::Elementary(Elementary::Int)),
                }
            } else {
                Body::Alias(self.type_expr()?)
            };
            self.skip_initial_value()?;
            self.eat(";");
            out.push(TypeDecl {
                name,
                place: Place {
                    file: self.file.to_string(),
                    line,
                },
                pack_mode: pack_mode.take(),
                body,
            });
        }
    }

    fn member(&mut self, out: &mut Vec<MemberDecl>) -> Result<(), DeclarationError> {
        self.pragmas()?;
        if self.eat_word("END_STRUCT") {
            self.at -= 1;
            return Ok(());
        }
        let line = self.line();
        let mut names = vec![self.name("a member name or END_STRUCT")?];
        while self.eat(",") {
            names.push(self.name("a member name")?);
        }
        if self.eat_word("AT") {
            while !matches!(self.peek(), Some(Token::Symbol(":")) | None) {
                self.at += 1;
            }
        }
        self.expect(":")?;
        let data_type = self.type_expr()?;
        self.skip_initial_value()?;
        self.expect(";")?;
        out.extend(names.into_iter().map(|name| MemberDecl {
            name,
            line,
            data_type: data_type.clone(),
        }));
        Ok(())
    }

    fn skip_initial_value(&mut self) -> Result<(), DeclarationError> {
        if self.eat(":=") {
            let mut depth = 0i32;
            loop {
                match self.peek() {
                    None => return Err(self.expected(";")),
                    Some(Token::Symbol(";")) if depth <= 0 => return Ok(()),
                    Some(Token::Symbol("(" | "[")) => depth += 1,
                    Some(Token::Symbol(")" | "]")) => depth -= 1,
                    _ => {}
                }
                self.at += 1;
            }
        }
        Ok(())
    }

    fn type_expr(&mut self) -> Result<TypeExpr, DeclarationError> {
        if self.eat_word("ARRAY") {
            self.depth += 1;
            if self.depth > 16 {
                return Err(self.error(Cause::TooDeep("ARRAY".into())));
            }
            self.expect("[")?;
            let mut ranges = vec![self.range()?];
            while self.eat(",") {
                ranges.push(self.range()?);
            }
            self.expect("]")?;
            if !self.eat_word("OF") {
                return Err(self.expected("OF"));
            }
            let element = self.type_expr()?;
            self.depth -= 1;
            if element == TypeExpr::Elementary(Elementary::Bit) {
                return Err(self.error(Cause::ArrayOfBits));
            }
            return Ok(ranges
                .into_iter()
                .rev()
                .fold(element, |element, (low, high)| TypeExpr::Array {
                    low,
                    high,
                    element: Box::new(element),
                }));
        }
        for unsized_word in ["POINTER", "REFERENCE", "INTERFACE", "PVOID"] {
            if self.peek().is_some_and(|t| t.is_word(unsized_word)) {
                return Err(self.error(Cause::Unsized("a POINTER, REFERENCE or INTERFACE")));
            }
        }
        let name = self.name("a type")?;
        if name.eq_ignore_ascii_case("STRING") || name.eq_ignore_ascii_case("WSTRING") {
            let characters = match (self.eat("("), self.eat("[")) {
                (false, false) => 80,
                _ => {
                    let length = self.bound()?;
                    if !(self.eat(")") || self.eat("]")) {
                        return Err(self.expected(")"));
                    }
                    usize::try_from(length)
                        .map_err(|_| self.error(Cause::Bound(length.to_string())))?
                }
            };
            let unit = if name.eq_ignore_ascii_case("WSTRING") {
                2
            } else {
                1
            };
            return Ok(TypeExpr::String {
                bytes: unit * (characters + 1),
            });
        }
        Ok(match Elementary::parse(&name) {
            Some(e) => TypeExpr::Elementary(e),
            None => TypeExpr::Named(name),
        })
    }

    fn range(&mut self) -> Result<(i64, i64), DeclarationError> {
        let low = self.bound()?;
        self.expect("..")?;
        let high = self.bound()?;
        if high < low || i128::from(high) - i128::from(low) >= i128::from(MAX_ELEMENTS) {
            return Err(self.error(Cause::EmptyArray { low, high }));
        }
        Ok((low, high))
    }

    fn bound(&mut self) -> Result<i64, DeclarationError> {
        let negative = self.eat("-");
        match self.next() {
            Some(Token::Number(n)) => Ok(if negative { -n } else { n }),
            other => {
                self.at -= 1;
                let mut text = other.map_or_else(String::new, |t| t.text());
                // Name the whole expression the user wrote, up to `..` or `]`.
                while let Some(t) = self.tokens.get(self.at + 1).map(|t| &t.0) {
                    if matches!(t, Token::Symbol(".." | "]" | ",")) {
                        break;
                    }
                    text.push_str(&t.text());
                    self.at += 1;
                }
                Err(self.error(Cause::Bound(text)))
            }
        }
    }
}

/// More elements than any array of an image could have (and few enough that
/// no count overflows).
const MAX_ELEMENTS: u32 = 1 << 24;

/// `attribute 'pack_mode' := '0'` → `0`.
fn pack_mode_of(pragma: &str) -> Option<&str> {
    let rest = pragma.trim().strip_prefix("attribute")?.trim_start();
    let rest = rest.strip_prefix("'pack_mode'")?.trim_start();
    let rest = rest.strip_prefix(":=")?.trim();
    Some(rest.trim_matches('\''))
}

/// Every type declared in `source`.
pub fn parse(source: &Source) -> Result<Vec<TypeDecl>, DeclarationError> {
    let mut parser = Parser {
        tokens: lex(source)?,
        at: 0,
        file: &source.file,
        depth: 0,
    };
    let mut types = Vec::new();
    let mut pending_pack = None;
    while let Some(token) = parser.peek() {
        if let Token::Pragma(_) = token {
            pending_pack = parser.pragmas()?;
            continue;
        }
        if parser.eat_word("TYPE") {
            let before = types.len();
            parser.type_block(&mut types)?;
            if let (Some(pack), Some(first)) = (pending_pack.take(), types.get_mut(before)) {
                first.pack_mode = first.pack_mode.or(Some(pack));
            }
        } else {
            pending_pack = None;
            parser.at += 1;
        }
    }
    if types.is_empty() {
        return Err(DeclarationError {
            place: Place {
                file: source.file.clone(),
                line: source.first_line,
            },
            cause: Cause::NoTypes,
        });
    }
    Ok(types)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(text: &str) -> Result<Vec<TypeDecl>, DeclarationError> {
        parse(&Source {
            file: "t.st".into(),
            text: text.into(),
            first_line: 1,
        })
    }

    #[test]
    fn a_struct_with_its_attribute_arrays_and_lines() {
        let types = parsed(
            "(* outputs *)\n{attribute 'pack_mode' := '0'}\nTYPE ST_Out :\nSTRUCT\n  TxCounter, RxCounter : UINT;\n  Msg : ARRAY [1..10] OF ST_Msg := [10(0)];\nEND_STRUCT\nEND_TYPE\n",
        )
        .expect("parses");
        assert_eq!(types.len(), 1);
        assert_eq!(types[0].pack_mode, Some(0));
        assert_eq!(types[0].place.line, 3);
        let Body::Struct(members) = &types[0].body else {
            panic!("a struct")
        };
        assert_eq!(members.len(), 3);
        assert_eq!(members[1].name, "RxCounter");
        assert_eq!(members[2].line, 6);
        assert_eq!(
            members[2].data_type,
            TypeExpr::Array {
                low: 1,
                high: 10,
                element: Box::new(TypeExpr::Named("ST_Msg".into()))
            }
        );
    }

    #[test]
    fn what_cannot_be_sized_is_an_error_on_its_line() {
        let bound =
            parsed("TYPE A :\nSTRUCT\n  m : ARRAY [0..MAX_SLOTS-1] OF BYTE;\nEND_STRUCT\nEND_TYPE")
                .unwrap_err();
        assert_eq!(bound.place.line, 3);
        assert_eq!(bound.cause, Cause::Bound("MAX_SLOTS-1".into()));
        let pointer =
            parsed("TYPE A :\nSTRUCT\n  p : POINTER TO BYTE;\nEND_STRUCT\nEND_TYPE").unwrap_err();
        assert!(matches!(pointer.cause, Cause::Unsized(_)), "{pointer}");
        let not_st = parsed("#include <stdint.h>\nstruct x { int a; };").unwrap_err();
        assert_eq!(not_st.cause, Cause::NoTypes);
        let open = parsed("TYPE A :\n(* never closed").unwrap_err();
        assert!(matches!(open.cause, Cause::Unterminated(_)), "{open}");
    }
}
