//! A small command-line parser: options are taken out by name, whatever is left is an error.
//! (Hand-written instead of clap to keep build time down on small machines.)

use super::CliError;

pub struct Args {
    rest: Vec<String>,
}

impl Args {
    pub fn new(rest: Vec<String>) -> Self {
        Args { rest }
    }

    /// Removes a boolean flag; true if it was present.
    pub fn flag(&mut self, name: &str) -> bool {
        let before = self.rest.len();
        self.rest.retain(|a| a != name);
        self.rest.len() != before
    }

    /// Removes `NAME VALUE` or `NAME=VALUE` for any of `names`; the last occurrence wins.
    pub fn value(&mut self, names: &[&str]) -> Result<Option<String>, CliError> {
        let mut found = None;
        let mut i = 0;
        while i < self.rest.len() {
            let arg = &self.rest[i];
            if names.contains(&arg.as_str()) {
                if i + 1 >= self.rest.len() {
                    return Err(CliError::Usage(format!("{arg} needs a value")));
                }
                found = Some(self.rest.remove(i + 1));
                self.rest.remove(i);
            } else if let Some((_, v)) = arg.split_once('=').filter(|(n, _)| names.contains(n)) {
                found = Some(v.to_string());
                self.rest.remove(i);
            } else {
                i += 1;
            }
        }
        Ok(found)
    }

    pub fn required(&mut self, names: &[&str]) -> Result<String, CliError> {
        self.value(names)?
            .ok_or_else(|| CliError::Usage(format!("{} is required", names[0])))
    }

    /// Takes the remaining arguments as positionals; an unknown `-option` is an error later.
    pub fn positional(&mut self) -> Vec<String> {
        let (pos, opts): (Vec<String>, Vec<String>) =
            self.rest.drain(..).partition(|a| !a.starts_with('-'));
        self.rest = opts;
        pos
    }

    /// Fails on anything not taken out by the command.
    pub fn finish(&self) -> Result<(), CliError> {
        match self.rest.first() {
            None => Ok(()),
            Some(a) if a.starts_with('-') => Err(CliError::Usage(format!("unknown option {a}"))),
            Some(a) => Err(CliError::Usage(format!("unexpected argument '{a}'"))),
        }
    }
}

/// A number option; `what` names it in the error.
pub fn parse_f32(what: &str, s: &str) -> Result<f32, CliError> {
    s.trim()
        .parse::<f32>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| CliError::Failure(format!("{what} must be a number, got '{s}'")))
}

/// `X,Y` as two numbers.
pub fn parse_pair(what: &str, s: &str) -> Result<[f32; 2], CliError> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 2 {
        return Err(CliError::Failure(format!(
            "{what} must be two numbers X,Y, got '{s}'"
        )));
    }
    Ok([parse_f32(what, parts[0])?, parse_f32(what, parts[1])?])
}

/// A comma-separated list of numbers.
pub fn parse_list(what: &str, s: &str) -> Result<Vec<f32>, CliError> {
    s.split(',').map(|p| parse_f32(what, p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(s: &str) -> Args {
        Args::new(s.split_whitespace().map(String::from).collect())
    }

    #[test]
    fn values_flags_and_leftovers() {
        let mut a = args("--display d.png -o=o.png --no-blur --lambda-e 0.3 --lambda-e 0.5 extra");
        assert_eq!(a.value(&["--display"]).unwrap().as_deref(), Some("d.png"));
        assert_eq!(
            a.value(&["-o", "--output"]).unwrap().as_deref(),
            Some("o.png")
        );
        assert!(a.flag("--no-blur") && !a.flag("--no-fov"));
        assert_eq!(a.value(&["--lambda-e"]).unwrap().as_deref(), Some("0.5"));
        assert!(matches!(a.finish(), Err(CliError::Usage(m)) if m.contains("extra")));
        assert!(matches!(
            args("--display").value(&["--display"]),
            Err(CliError::Usage(_))
        ));
    }

    #[test]
    fn numbers() {
        assert_eq!(parse_pair("p", "0.65,0.5").unwrap(), [0.65, 0.5]);
        assert!(parse_pair("p", "0.65").is_err());
        assert!(parse_f32("x", "nan").is_err());
        assert_eq!(parse_list("l", "0.2,1").unwrap(), vec![0.2, 1.0]);
    }
}
