//! The Vehicle's contact table: the built-in one (computed once per process from the S1002 and
//! UIC60 profiles), a table file (`contact_table`), or one computed from measured profiles
//! (`wheel_profile`, `rail_profile`).

use std::sync::{Arc, Mutex, OnceLock};

use super::Vehicle;
use crate::contact::table::{ContactSpline, ContactTable};
use crate::contact::{compute_table, ContactSettings, Profile};
use crate::models::data_file::{read_data_file, resolve};
use crate::models::ModelError;

/// Half-width (m) of the moving average ([`crate::contact::smooth::smoothed`]) that makes the
/// computed S1002/UIC60 table fit for the model's cubic splines: the rigid contact jumps across
/// the tread and onto the flange, and a spline through a jump overshoots.
pub const BUILTIN_SMOOTHING: f64 = 0.05e-3;

/// A contact table with its splines, shared between instances.
pub(super) type SharedTable = (Arc<ContactTable>, Arc<ContactSpline>);

/// The built-in table and its splines, computed once per process (shared by every instance,
/// kept across fmi2Reset).
pub(super) fn builtin() -> Result<&'static SharedTable, ModelError> {
    static BUILTIN: OnceLock<Result<SharedTable, String>> = OnceLock::new();
    BUILTIN
        .get_or_init(|| {
            let raw = crate::contact::default_table().map_err(|e| e.to_string())?;
            let table = crate::contact::smooth::smoothed(&raw, BUILTIN_SMOOTHING);
            let spline = ContactSpline::new(&table);
            Ok((Arc::new(table), Arc::new(spline)))
        })
        .as_ref()
        .map_err(|e| ModelError::Other(format!("the built-in contact table: {e}")))
}

/// The contact table used when `contact_table` is empty: S1002 wheels on UIC60 rails inclined
/// 1:40, standard gauge, computed from the profiles ([`crate::contact::default_table`]) and
/// smoothed over [`BUILTIN_SMOOTHING`] in y (the same as `railuq-fmu contact --smooth 0.05`).
pub fn builtin_contact_table() -> Result<ContactTable, ModelError> {
    builtin().map(|(t, _)| t.as_ref().clone())
}

impl Vehicle {
    /// The contact table `contact_table` names (the built-in one when empty), with its splines.
    pub(super) fn load_table(&self) -> Result<SharedTable, ModelError> {
        let profiles = !(self.wheel_profile.is_empty() && self.rail_profile.is_empty());
        if self.contact_table.is_empty() {
            return if profiles {
                self.profile_table()
            } else {
                builtin().cloned()
            };
        }
        if profiles {
            return Err(ModelError::Other(
                "contact_table and wheel_profile / rail_profile are both set: the table is \
                 either read from a file or computed from the profiles (leave contact_table \
                 empty to compute it)"
                    .into(),
            ));
        }
        let text = read_data_file(
            "contact_table",
            &self.contact_table,
            self.resource_dir.as_deref(),
        )
        .map_err(ModelError::Other)?;
        let shown = resolve(&self.contact_table, self.resource_dir.as_deref());
        let table = ContactTable::parse_csv(&text)
            .map_err(|e| ModelError::Other(format!("contact_table '{}': {e}", shown.display())))?;
        let (lo, hi) = table.range();
        if !(lo < 0.0 && hi > 0.0) {
            return Err(ModelError::Other(format!(
                "contact_table '{}': y must cover both signs around 0 (the right wheel reads \
                 the row at -y)",
                shown.display()
            )));
        }
        let spline = Arc::new(ContactSpline::new(&table));
        Ok((Arc::new(table), spline))
    }

    /// The table computed from `wheel_profile` and `rail_profile` (S1002 and UIC60 where one
    /// is empty) with the built-in table's settings (rails at 1:40, standard gauge) and
    /// smoothing; computed once per process for the same two files' contents.
    fn profile_table(&self) -> Result<SharedTable, ModelError> {
        let dir = self.resource_dir.as_deref();
        let read = |what: &str, name: &str| -> Result<String, ModelError> {
            if name.is_empty() {
                Ok(String::new())
            } else {
                read_data_file(what, name, dir).map_err(ModelError::Other)
            }
        };
        let (wheel, rail) = (
            read("wheel_profile", &self.wheel_profile)?,
            read("rail_profile", &self.rail_profile)?,
        );
        type Cache = Mutex<Vec<((String, String), SharedTable)>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        let cache = CACHE.get_or_init(|| Mutex::new(Vec::new()));
        let key = (wheel, rail);
        if let Some((_, t)) = cache
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .find(|(k, _)| *k == key)
        {
            return Ok(t.clone());
        }
        let mut s = ContactSettings::default();
        let shown = |name: &str| resolve(name, dir).display().to_string();
        if !key.0.is_empty() {
            s.wheel = Profile::wheel_from_csv(&key.0, s.rolling_circle).map_err(|e| {
                ModelError::Other(format!(
                    "wheel_profile '{}': {e}",
                    shown(&self.wheel_profile)
                ))
            })?;
        }
        if !key.1.is_empty() {
            s.rail = Profile::rail_from_csv(&key.1).map_err(|e| {
                ModelError::Other(format!("rail_profile '{}': {e}", shown(&self.rail_profile)))
            })?;
        }
        let raw = compute_table(&s).map_err(|e| {
            ModelError::Other(format!(
                "the contact table of wheel_profile / rail_profile: {e}"
            ))
        })?;
        let table = crate::contact::smooth::smoothed(&raw, BUILTIN_SMOOTHING);
        let spline = Arc::new(ContactSpline::new(&table));
        let shared = (Arc::new(table), spline);
        let mut c = cache.lock().unwrap_or_else(|e| e.into_inner());
        if c.len() >= 8 {
            c.remove(0);
        }
        c.push((key, shared.clone()));
        Ok(shared)
    }

    /// [`Self::load_table`] with the resources folder of `ctx` (tests).
    #[cfg(test)]
    pub(super) fn load_table_for_test(&mut self, ctx: &crate::models::InitContext) -> SharedTable {
        self.resource_dir = ctx.resource_dir.clone();
        self.load_table().unwrap()
    }
}
