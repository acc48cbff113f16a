//! Typed setting values, read from TOML or from text (environment variables, `contrastxr set`).
//! Parsing returns a sentence on any input; it never panics.

use std::fmt;

/// The shape of a setting's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Bool,
    Float,
    /// A non-negative integer.
    Count,
    /// Two numbers: `[x, y]` in TOML, `x,y` as text.
    Pair,
    /// This many numbers: `[a, b, c]` in TOML, `a,b,c` as text.
    Numbers(usize),
    Text,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Bool(bool),
    Float(f32),
    Count(u64),
    Pair([f32; 2]),
    Numbers(Vec<f32>),
    Text(String),
}

impl Kind {
    /// What a value of this kind is, for messages ("expected a number").
    pub fn describe(self) -> String {
        match self {
            Kind::Bool => "true or false".into(),
            Kind::Float => "a number".into(),
            Kind::Count => "a whole number >= 0".into(),
            Kind::Pair => "two numbers [x, y]".into(),
            Kind::Numbers(n) => format!("{n} numbers [a, b, ...]"),
            Kind::Text => "a string".into(),
        }
    }

    /// Parses the text form (environment variables and the command line).
    pub fn from_text(self, text: &str) -> Result<Value, String> {
        let t = text.trim();
        let expected = || format!("{t:?} is not {}", self.describe());
        match self {
            Kind::Bool => match t.to_ascii_lowercase().as_str() {
                "1" | "true" | "on" | "yes" => Ok(Value::Bool(true)),
                "" | "0" | "false" | "off" | "no" => Ok(Value::Bool(false)),
                _ => Err(expected()),
            },
            Kind::Float => t.parse().map(Value::Float).map_err(|_| expected()),
            Kind::Count => t.parse().map(Value::Count).map_err(|_| expected()),
            Kind::Pair => {
                let parts: Vec<Option<f32>> = t
                    .trim_start_matches('[')
                    .trim_end_matches(']')
                    .split(',')
                    .map(|p| p.trim().parse().ok())
                    .collect();
                match parts.as_slice() {
                    [Some(x), Some(y)] => Ok(Value::Pair([*x, *y])),
                    _ => Err(format!("{t:?} is not X,Y")),
                }
            }
            Kind::Numbers(n) => {
                let parts: Option<Vec<f32>> = t
                    .trim_start_matches('[')
                    .trim_end_matches(']')
                    .split(',')
                    .map(|p| p.trim().parse().ok())
                    .collect();
                match parts {
                    Some(v) if v.len() == n => Ok(Value::Numbers(v)),
                    _ => Err(format!("{t:?} is not {n} numbers separated by commas")),
                }
            }
            Kind::Text => Ok(Value::Text(t.to_string())),
        }
    }

    /// Converts a TOML value; the error names the TOML type found.
    pub fn from_toml(self, value: &toml_edit::Value) -> Result<Value, String> {
        use toml_edit::Value as T;
        let wrong = || {
            format!(
                "expected {}, found {}",
                self.describe(),
                article(value.type_name())
            )
        };
        let number = |v: &T| match v {
            T::Float(f) => Some(*f.value() as f32),
            T::Integer(i) => Some(*i.value() as f32),
            _ => None,
        };
        match (self, value) {
            (Kind::Bool, T::Boolean(b)) => Ok(Value::Bool(*b.value())),
            (Kind::Float, v) => number(v).map(Value::Float).ok_or_else(wrong),
            (Kind::Count, T::Integer(i)) => u64::try_from(*i.value())
                .map(Value::Count)
                .map_err(|_| format!("expected {}, found {}", self.describe(), i.value())),
            (Kind::Pair, T::Array(a)) => {
                let numbers: Vec<Option<f32>> = a.iter().map(number).collect();
                match numbers.as_slice() {
                    [Some(x), Some(y)] => Ok(Value::Pair([*x, *y])),
                    _ => Err(format!("expected {}", self.describe())),
                }
            }
            (Kind::Numbers(n), T::Array(a)) => {
                let numbers: Option<Vec<f32>> = a.iter().map(number).collect();
                match numbers {
                    Some(v) if v.len() == n => Ok(Value::Numbers(v)),
                    _ => Err(format!("expected {}", self.describe())),
                }
            }
            (Kind::Text, T::String(s)) => Ok(Value::Text(s.value().clone())),
            _ => Err(wrong()),
        }
    }
}

fn article(type_name: &str) -> String {
    let vowel = type_name.starts_with(['a', 'e', 'i', 'o', 'u']);
    format!("{} {type_name}", if vowel { "an" } else { "a" })
}

/// An f32 as the shortest f64 that prints the same, so 0.4 is written `0.4`, not 0.4000000059.
pub(super) fn short_f64(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

impl Value {
    pub fn to_toml(&self) -> toml_edit::Value {
        match self {
            Value::Bool(b) => (*b).into(),
            Value::Float(f) => short_f64(*f).into(),
            Value::Count(n) => i64::try_from(*n).unwrap_or(i64::MAX).into(),
            Value::Pair([x, y]) => {
                toml_edit::Value::Array([short_f64(*x), short_f64(*y)].into_iter().collect())
            }
            Value::Numbers(v) => v.iter().map(|x| short_f64(*x)).collect(),
            Value::Text(s) => s.as_str().into(),
        }
    }
}

/// TOML syntax, for `config print` and the log.
impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Float(x) => write!(f, "{}", short_f64(*x)),
            other => write!(f, "{}", other.to_toml().to_string().trim()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_forms() {
        assert_eq!(Kind::Bool.from_text(" ON "), Ok(Value::Bool(true)));
        assert_eq!(Kind::Bool.from_text("0"), Ok(Value::Bool(false)));
        assert!(Kind::Bool.from_text("maybe").is_err());
        assert_eq!(Kind::Float.from_text("0.6"), Ok(Value::Float(0.6)));
        assert_eq!(Kind::Pair.from_text("1, 2"), Ok(Value::Pair([1.0, 2.0])));
        assert!(Kind::Pair.from_text("1").is_err());
        assert_eq!(
            Kind::Numbers(3).from_text("[1, 2,3]"),
            Ok(Value::Numbers(vec![1.0, 2.0, 3.0]))
        );
        assert!(Kind::Numbers(3).from_text("1,2").is_err());
        assert!(Kind::Count.from_text("-1").is_err());
    }

    #[test]
    fn toml_types_are_checked() {
        let v = |s: &str| s.parse::<toml_edit::Value>().unwrap();
        assert_eq!(Kind::Float.from_toml(&v("1")), Ok(Value::Float(1.0)));
        assert_eq!(
            Kind::Float.from_toml(&v("\"high\"")),
            Err("expected a number, found a string".into())
        );
        assert!(Kind::Count.from_toml(&v("-3")).is_err());
        assert_eq!(
            Kind::Pair.from_toml(&v("[0.5, 1]")),
            Ok(Value::Pair([0.5, 1.0]))
        );
        assert!(Kind::Pair.from_toml(&v("[0.5]")).is_err());
        assert_eq!(
            Kind::Numbers(3).from_toml(&v("[0, -0.5, 2]")),
            Ok(Value::Numbers(vec![0.0, -0.5, 2.0]))
        );
        assert!(Kind::Numbers(3).from_toml(&v("[0, 1]")).is_err());
        assert!(Kind::Numbers(3).from_toml(&v("[0, 1, \"x\"]")).is_err());
    }

    #[test]
    fn displays_as_toml() {
        assert_eq!(Value::Float(0.4).to_string(), "0.4");
        assert_eq!(Value::Text("a\"b".into()).to_string(), "'a\"b'");
        assert_eq!(Value::Pair([0.65, 0.13]).to_string(), "[0.65, 0.13]");
    }
}
