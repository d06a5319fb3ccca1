//! Techniques as data: what a plug-in declares ([`Technique`], [`TechniqueValue`]) and how a
//! render's choices for them reach it ([`PluginTechniques`], read through
//! [`IntegratorContext::technique`](super::IntegratorContext::technique)). The registry of a
//! scene's techniques and the global integrator's own are `crate::technique`'s.

use crate::features::Features;

/// One value a technique can take.
#[derive(Clone, Copy, Debug)]
pub struct TechniqueValue {
    /// Its name (`NAME=VALUE`).
    pub name: &'static str,
    /// What it does.
    pub summary: &'static str,
    /// Whether it converges to the scene's exact image in a scene with these features
    /// (false for an approximation, such as single scattering only): only such values may
    /// render a reference. [`always`] for an unbiased estimator, [`never()`] for an
    /// approximation.
    pub converges: fn(&Features) -> bool,
}

/// [`TechniqueValue::converges`] of an unbiased estimator.
pub fn always(_: &Features) -> bool {
    true
}

/// [`TechniqueValue::converges`] of an approximation.
pub fn never(_: &Features) -> bool {
    false
}

/// A technique: a named choice between estimators, declared as data.
#[derive(Debug)]
pub struct Technique {
    /// Its name (`NAME=VALUE`).
    pub name: &'static str,
    /// What it chooses.
    pub summary: &'static str,
    /// Its values.
    pub values: &'static [TechniqueValue],
    /// The value used unless one is given (one of `values`).
    pub default: &'static str,
    /// The scenes it applies to, in words.
    pub applies_to: &'static str,
}

impl Technique {
    /// The value named `value`, with the error a user sees when there is none.
    pub fn value(&self, value: &str) -> Result<&'static TechniqueValue, TechniqueError> {
        self.values
            .iter()
            .find(|v| v.name == value)
            .ok_or_else(|| TechniqueError::BadValue {
                technique: self.name,
                value: value.to_string(),
                expected: self
                    .values
                    .iter()
                    .map(|v| v.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }
}

/// A bad technique name, value or use.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TechniqueError {
    /// No technique has this name.
    #[error(
        "unknown technique \"{name}\" (known in this scene: {known}; a plug-in technique is known where a material of the scene declares it)"
    )]
    Unknown {
        /// The name given.
        name: String,
        /// The registered names.
        known: String,
    },
    /// The technique has no such value.
    #[error("technique {technique}: unknown value \"{value}\" (expected one of {expected})")]
    BadValue {
        /// The technique.
        technique: &'static str,
        /// The value given.
        value: String,
        /// Its values.
        expected: String,
    },
    /// Not of the form `NAME=VALUE`.
    #[error("\"{0}\": expected NAME=VALUE (e.g. lighting=nee)")]
    Malformed(String),
    /// More plug-in techniques chosen than [`MAX_PLUGIN_CHOICES`].
    #[error("at most {MAX_PLUGIN_CHOICES} plug-in techniques can be set at once")]
    TooMany,
    /// The technique does not apply to the scene.
    #[error(
        "technique {technique}={value} does not apply to this scene: {technique} applies to {applies_to}"
    )]
    NotApplicable {
        /// The technique.
        technique: &'static str,
        /// The value given.
        value: String,
        /// What it applies to.
        applies_to: &'static str,
    },
}

/// The most plug-in techniques one render sets to a value other than their default.
pub const MAX_PLUGIN_CHOICES: usize = 8;

/// The values chosen for plug-in techniques, by name; a technique not listed takes its
/// default. Plain data (`Copy`), read by plug-ins through
/// [`IntegratorContext::technique`](super::IntegratorContext::technique).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PluginTechniques {
    /// `(technique, value)`, sorted by name, `len` of them used.
    chosen: [(&'static str, &'static str); MAX_PLUGIN_CHOICES],
    len: usize,
}

impl PluginTechniques {
    /// The value chosen for technique `name`; `None`: its default.
    pub fn get(&self, name: &str) -> Option<&'static str> {
        self.iter().find(|(n, _)| *n == name).map(|(_, v)| v)
    }

    /// The chosen `(technique, value)` pairs, by name.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, &'static str)> + '_ {
        self.chosen[..self.len].iter().copied()
    }

    /// These choices with technique `name` set to `value` (not checked against any
    /// declaration: [`Techniques::set`](crate::technique::Techniques::set) checks).
    ///
    /// # Errors
    /// When [`MAX_PLUGIN_CHOICES`] other techniques are chosen already.
    pub fn with(
        mut self,
        name: &'static str,
        value: &'static str,
    ) -> Result<PluginTechniques, TechniqueError> {
        self.remove(name);
        if self.len == MAX_PLUGIN_CHOICES {
            return Err(TechniqueError::TooMany);
        }
        let at = self.chosen[..self.len].partition_point(|(n, _)| *n < name);
        self.chosen.copy_within(at..self.len, at + 1);
        self.chosen[at] = (name, value);
        self.len += 1;
        Ok(self)
    }

    /// Drops the choice for `name` (it takes its default).
    pub(crate) fn remove(&mut self, name: &str) {
        if let Some(i) = self.chosen[..self.len].iter().position(|(n, _)| *n == name) {
            self.chosen.copy_within(i + 1..self.len, i);
            self.len -= 1;
            self.chosen[self.len] = ("", "");
        }
    }
}
