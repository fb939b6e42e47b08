//! Each model declares every variable once, in one line of a `variables!` table: its name,
//! value reference, unit, where its value lives (or how it is computed), its start value,
//! variability, the check a new value must pass, and its description. From that one line come
//!
//! - the value-reference constant (`VR_…`);
//! - the entry of the model's [`Variable`] list (the FMI layer writes modelDescription.xml from it);
//! - the get and set dispatch ([`Table::get_real`], [`Table::set_real`], …);
//! - the defaults ([`Table::apply_defaults`]) and the parameters of a saved state
//!   ([`Table::save_parameters`], [`Table::restore_parameters`]).
//!
//! Adding a parameter is one line of the table (plus the field the equations read, where the
//! model keeps its parameters in named fields).
#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};

use super::{Causality, ModelError, SetResult, Start, StateReader, StateWriter, VarType, Variable};

/// How a variable of model `M` is read and (for parameters) written.
pub enum Access<M: 'static> {
    /// A Real: getter, and a checked setter for parameters.
    Real(fn(&M) -> f64, Option<fn(&mut M, f64) -> SetResult>),
    /// An Integer.
    Integer(fn(&M) -> i32, Option<fn(&mut M, i32) -> SetResult>),
    /// A String.
    String(fn(&M) -> String, Option<fn(&mut M, &str) -> SetResult>),
}

/// One line of a model's variable table: the interface description and its access.
pub struct Binding<M: 'static> {
    /// The variable as the FMI layer sees it.
    pub var: Variable,
    /// Getter and setter.
    pub access: Access<M>,
}

const PLACEHOLDER: Variable = Variable::real_output("", 0, None, "");

/// The [`Variable`] list of a table, in table order (for [`super::ModelInfo::variables`]).
pub const fn variable_list<M, const N: usize>(bindings: &[Binding<M>; N]) -> [Variable; N] {
    let mut out = [PLACEHOLDER; N];
    let mut i = 0;
    while i < N {
        out[i] = bindings[i].var;
        i += 1;
    }
    out
}

/// A model's variable table (sorted by value reference; a test checks it).
pub struct Table<M: 'static>(pub &'static [Binding<M>]);

impl<M> Table<M> {
    fn find(&self, vr: u32) -> Option<&'static Binding<M>> {
        let b = self.0;
        b.binary_search_by_key(&vr, |b| b.var.vr)
            .ok()
            .map(|i| &b[i])
    }

    /// Reads a Real variable.
    pub fn get_real(&self, m: &M, vr: u32) -> Result<f64, ModelError> {
        match self.find(vr).map(|b| &b.access) {
            Some(Access::Real(get, _)) => Ok(get(m)),
            _ => Err(ModelError::NoSuchVariable(VarType::Real, vr)),
        }
    }

    /// Writes a Real parameter after its check.
    pub fn set_real(&self, m: &mut M, vr: u32, value: f64) -> SetResult {
        match self.find(vr).map(|b| &b.access) {
            Some(Access::Real(_, Some(set))) => set(m, value),
            _ => Err(ModelError::NoSuchVariable(VarType::Real, vr)),
        }
    }

    /// Reads an Integer variable.
    pub fn get_integer(&self, m: &M, vr: u32) -> Result<i32, ModelError> {
        match self.find(vr).map(|b| &b.access) {
            Some(Access::Integer(get, _)) => Ok(get(m)),
            _ => Err(ModelError::NoSuchVariable(VarType::Integer, vr)),
        }
    }

    /// Writes an Integer parameter after its check.
    pub fn set_integer(&self, m: &mut M, vr: u32, value: i32) -> SetResult {
        match self.find(vr).map(|b| &b.access) {
            Some(Access::Integer(_, Some(set))) => set(m, value),
            _ => Err(ModelError::NoSuchVariable(VarType::Integer, vr)),
        }
    }

    /// Reads a String variable.
    pub fn get_string(&self, m: &M, vr: u32) -> Result<String, ModelError> {
        match self.find(vr).map(|b| &b.access) {
            Some(Access::String(get, _)) => Ok(get(m)),
            _ => Err(ModelError::NoSuchVariable(VarType::String, vr)),
        }
    }

    /// Writes a String parameter after its check.
    pub fn set_string(&self, m: &mut M, vr: u32, value: &str) -> SetResult {
        match self.find(vr).map(|b| &b.access) {
            Some(Access::String(_, Some(set))) => set(m, value),
            _ => Err(ModelError::NoSuchVariable(VarType::String, vr)),
        }
    }

    /// Sets every parameter to its start value (a start value that fails its own check is a
    /// bug of the table; the models' tests read every start value back).
    pub fn apply_defaults(&self, m: &mut M) {
        for b in self.0 {
            let result = match (&b.access, b.var.start) {
                (Access::Real(_, Some(set)), Start::Real(Some(v))) => set(m, v),
                (Access::Integer(_, Some(set)), Start::Integer(Some(v))) => set(m, v),
                (Access::String(_, Some(set)), Start::String(Some(v))) => set(m, v),
                _ => Ok(None),
            };
            debug_assert!(result.is_ok(), "{}: start value refused", b.var.name);
        }
    }

    fn parameters(&self) -> impl Iterator<Item = &'static Binding<M>> {
        self.0
            .iter()
            .filter(|b| b.var.causality == Causality::Parameter)
    }

    /// Appends the value of every parameter, in table order.
    pub fn save_parameters(&self, m: &M, out: &mut StateWriter) {
        for b in self.parameters() {
            match &b.access {
                Access::Real(get, _) => out.f64(get(m)),
                Access::Integer(get, _) => out.u64(get(m) as i64 as u64),
                Access::String(get, _) => out.str(&get(m)),
            }
        }
    }

    /// Writes the head of a state that keeps a resource folder: the state format `version`,
    /// the parameters of `m` ([`Table::save_parameters`]) and the folder (empty: none).
    pub fn save_head(
        &self,
        m: &M,
        version: u64,
        resource_dir: Option<&Path>,
        out: &mut StateWriter,
    ) {
        out.u64(version);
        self.save_parameters(m, out);
        out.str(&resource_dir.map_or(String::new(), |d| d.display().to_string()));
    }

    /// Reads what [`Table::save_head`] wrote into `m`, refusing another format `version`;
    /// returns the resource folder.
    pub fn restore_head(
        &self,
        m: &mut M,
        version: u64,
        input: &mut StateReader<'_>,
    ) -> Result<Option<PathBuf>, ModelError> {
        let found = input.u64()?;
        if found != version {
            return Err(ModelError::CorruptState(format!(
                "state version {found}, expected {version}"
            )));
        }
        self.restore_parameters(m, input)?;
        let dir = input.str()?;
        Ok((!dir.is_empty()).then(|| PathBuf::from(dir)))
    }

    /// Reads what [`Table::save_parameters`] wrote; each value passes its check again.
    pub fn restore_parameters(
        &self,
        m: &mut M,
        input: &mut StateReader<'_>,
    ) -> Result<(), ModelError> {
        let corrupt = |b: &Binding<M>, e: ModelError| {
            ModelError::CorruptState(format!("parameter '{}': {e}", b.var.name))
        };
        for b in self.parameters() {
            match &b.access {
                Access::Real(_, Some(set)) => {
                    let v = input.f64()?;
                    set(m, v).map_err(|e| corrupt(b, e))?;
                }
                Access::Integer(_, Some(set)) => {
                    let v = input.u64()? as i64;
                    let v = i32::try_from(v).map_err(|_| {
                        ModelError::CorruptState(format!("{}: {v} out of range", b.var.name))
                    })?;
                    set(m, v).map_err(|e| corrupt(b, e))?;
                }
                Access::String(_, Some(set)) => {
                    let v = input.str()?;
                    set(m, &v).map_err(|e| corrupt(b, e))?;
                }
                _ => {
                    return Err(ModelError::CorruptState(format!(
                        "parameter '{}' is not settable",
                        b.var.name
                    )))
                }
            }
        }
        Ok(())
    }
}

/// Accepts any finite value.
pub fn finite(name: &'static str, value: f64) -> SetResult {
    super::require_finite(name, value).map(|()| None)
}

/// Accepts finite values > 0.
pub fn positive(name: &'static str, value: f64) -> SetResult {
    super::require_positive(name, value).map(|()| None)
}

/// Accepts finite values ≥ 0.
pub fn non_negative(name: &'static str, value: f64) -> SetResult {
    super::require_non_negative(name, value).map(|()| None)
}

/// Accepts every Integer.
pub fn any_integer(_name: &'static str, _value: i32) -> SetResult {
    Ok(None)
}

/// Accepts every String.
pub fn any_string(_name: &'static str, _value: &str) -> SetResult {
    Ok(None)
}

/// Declares a model's variables, one per line, in value-reference order:
///
/// ```text
/// variables! {
///     static TABLE: [Model as m];
///     real_parameter("K", VR_K = 1, Some("N/m"), m.k, 100.0, Tunable, positive, "Stiffness"),
///     integer_parameter("seed", VR_SEED = 44, m.p.seed, 1, any_integer, "Seed ..."),
///     string_parameter("file", VR_FILE = 46, m.p.file, "", any_string, "CSV ..."),
///     calculated("G", VR_G = 50, None, m.hertz(), "Hertz constant"),
///     calculated_string("solver.kernel", VR_KERNEL = 53, m.kernel_name(), "Kernel ..."),
///     output("q", VR_Q = 10, Some("m"), m.y[0], "Displacement"),
/// }
/// ```
///
/// A parameter line names the place its value is stored (read by the getter, assigned by
/// the setter after the check `check(name, value)`); `real_parameter` takes an optional
/// trailing `min = x` and then `max = y` (the XML `min` and `max` attributes; the check
/// must refuse values outside them). Outputs and calculated parameters give an
/// expression of the model `m` (a `calculated_string` one of type `String`). The macro
/// defines the `VR_…` constants, `TABLE` (a [`Table`]) and `VARIABLES` (the [`Variable`]
/// list).
macro_rules! variables {
    (
        static $table:ident: [$model:ty as $m:ident];
        $( $kind:ident $args:tt ),* $(,)?
    ) => {
        $( $crate::models::table::variables!(@vr $kind $args); )*
        const BINDINGS: [$crate::models::table::Binding<$model>;
            [$(stringify!($kind)),*].len()] = [
            $( $crate::models::table::variables!(@bind $model, $m, $kind $args) ),*
        ];
        /// The variable table: description, getters and checked setters, in vr order.
        pub static $table: $crate::models::table::Table<$model> =
            $crate::models::table::Table(&BINDINGS);
        /// The variable list (sorted by value reference), as modelDescription.xml shows it.
        pub static VARIABLES: [$crate::models::Variable; [$(stringify!($kind)),*].len()] =
            $crate::models::table::variable_list(&BINDINGS);
    };
    (@vr $kind:ident ($name:literal, $vr_name:ident = $vr:literal, $($rest:tt)*)) => {
        #[doc = concat!("Value reference of `", $name, "`.")]
        pub const $vr_name: u32 = $vr;
    };
    (@bind $model:ty, $m:ident, real_parameter ($name:literal, $vr_name:ident = $vr:literal,
        $unit:expr, $place:expr, $start:expr, $variability:ident, $check:expr, $desc:literal
        $(, min = $min:expr)? $(, max = $max:expr)?)) => {
        $crate::models::table::Binding {
            var: $crate::models::Variable::real_parameter(
                $name, $vr, $start, $crate::models::Variability::$variability, $unit, $desc,
            )$(.with_min(Some($min)))?$(.with_max(Some($max)))?,
            access: $crate::models::table::Access::Real(
                |$m: &$model| $place,
                Some(|$m: &mut $model, value: f64| {
                    let warning = ($check)($name, value)?;
                    $place = value;
                    Ok(warning)
                }),
            ),
        }
    };
    (@bind $model:ty, $m:ident, integer_parameter ($name:literal, $vr_name:ident = $vr:literal,
        $place:expr, $start:expr, $check:expr, $desc:literal)) => {
        $crate::models::table::Binding {
            var: $crate::models::Variable::integer_parameter($name, $vr, $start, $desc),
            access: $crate::models::table::Access::Integer(
                |$m: &$model| $place,
                Some(|$m: &mut $model, value: i32| {
                    let warning = ($check)($name, value)?;
                    $place = value;
                    Ok(warning)
                }),
            ),
        }
    };
    (@bind $model:ty, $m:ident, string_parameter ($name:literal, $vr_name:ident = $vr:literal,
        $place:expr, $start:expr, $check:expr, $desc:literal)) => {
        $crate::models::table::Binding {
            var: $crate::models::Variable::string_parameter($name, $vr, $start, $desc),
            access: $crate::models::table::Access::String(
                |$m: &$model| $place.clone(),
                Some(|$m: &mut $model, value: &str| {
                    let warning = ($check)($name, value)?;
                    $place = value.to_string();
                    Ok(warning)
                }),
            ),
        }
    };
    (@bind $model:ty, $m:ident, calculated ($name:literal, $vr_name:ident = $vr:literal,
        $unit:expr, $get:expr, $desc:literal)) => {
        $crate::models::table::Binding {
            var: $crate::models::Variable::calculated_parameter($name, $vr, $unit, $desc),
            access: $crate::models::table::Access::Real(|$m: &$model| $get, None),
        }
    };
    (@bind $model:ty, $m:ident, calculated_string ($name:literal, $vr_name:ident = $vr:literal,
        $get:expr, $desc:literal)) => {
        $crate::models::table::Binding {
            var: $crate::models::Variable::calculated_string($name, $vr, $desc),
            access: $crate::models::table::Access::String(|$m: &$model| $get, None),
        }
    };
    (@bind $model:ty, $m:ident, output ($name:literal, $vr_name:ident = $vr:literal,
        $unit:expr, $get:expr, $desc:literal)) => {
        $crate::models::table::Binding {
            var: $crate::models::Variable::real_output($name, $vr, $unit, $desc),
            access: $crate::models::table::Access::Real(|$m: &$model| $get, None),
        }
    };
}
pub(crate) use variables;

/// Inside an `impl Model`, the [`Model`](crate::models::Model) methods that only read or write
/// a variable of the table `$table` (a [`Table`]): `get_real -> f64` is a getter and
/// `set_real(f64)` a setter, each forwarding to the table's method of the same name.
macro_rules! table_accessors {
    ($table:ident;) => {};
    ($table:ident; $get:ident -> $t:ty $(, $($rest:tt)*)?) => {
        fn $get(&self, vr: u32) -> Result<$t, $crate::models::ModelError> {
            $table.$get(self, vr)
        }
        $crate::models::table::table_accessors!($table; $($($rest)*)?);
    };
    ($table:ident; $set:ident($t:ty) $(, $($rest:tt)*)?) => {
        fn $set(&mut self, vr: u32, value: $t) -> $crate::models::SetResult {
            $table.$set(self, vr, value)
        }
        $crate::models::table::table_accessors!($table; $($($rest)*)?);
    };
}
pub(crate) use table_accessors;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::{StateReader, StateWriter};

    #[derive(Debug, Default, PartialEq)]
    pub struct Toy {
        a: f64,
        n: i32,
        s: String,
        state: f64,
    }

    fn odd(name: &'static str, v: i32) -> SetResult {
        if v % 2 == 1 {
            Ok(None)
        } else {
            Err(ModelError::invalid(name, v, "must be odd"))
        }
    }

    variables! {
        static TOY: [Toy as t];
        real_parameter("a", VR_A = 0, Some("m"), t.a, 2.5, Tunable, positive, "A length", min = 0.0),
        integer_parameter("n", VR_N = 1, t.n, 3, odd, "An odd count"),
        string_parameter("s", VR_S = 2, t.s, "x", any_string, "A name"),
        calculated("twice_a", VR_TWICE = 3, Some("m"), 2.0 * t.a, "2 a"),
        output("state", VR_STATE = 10, None, t.state, "The state"),
    }

    #[test]
    fn one_line_gives_list_dispatch_defaults_and_state() {
        assert_eq!(VARIABLES.len(), 5);
        assert_eq!(VARIABLES[0].min, Some(0.0));
        assert_eq!(VARIABLES[4].vr, VR_STATE);
        let mut t = Toy::default();
        TOY.apply_defaults(&mut t);
        assert_eq!((t.a, t.n, t.s.as_str()), (2.5, 3, "x"));
        assert_eq!(TOY.get_real(&t, VR_TWICE).unwrap(), 5.0);
        assert!(TOY.set_real(&mut t, VR_A, -1.0).is_err());
        assert_eq!(t.a, 2.5, "a refused value leaves the parameter");
        assert!(TOY.set_integer(&mut t, VR_N, 4).is_err());
        assert!(
            TOY.set_real(&mut t, VR_STATE, 1.0).is_err(),
            "outputs are not settable"
        );
        assert!(TOY.get_integer(&t, VR_A).is_err(), "wrong type");
        TOY.set_string(&mut t, VR_S, "y").unwrap();
        TOY.set_real(&mut t, VR_A, 7.0).unwrap();
        let mut w = StateWriter::default();
        TOY.save_parameters(&t, &mut w);
        let mut u = Toy::default();
        TOY.restore_parameters(&mut u, &mut StateReader::new(&w.bytes))
            .unwrap();
        assert_eq!((u.a, u.n, u.s.as_str()), (7.0, 3, "y"));
        assert!(TOY
            .restore_parameters(&mut u, &mut StateReader::new(&w.bytes[..9]))
            .is_err());
    }
}
