//! `ringmesh._ringmesh`: the library called from Python (issue 36). Every
//! computation is the library's; this crate converts arguments in (numpy
//! arrays checked for shape and dtype, keywords into the library's settings,
//! validated by the library), results out (vectors handed to numpy without a
//! copy, reports as dicts), maps the library's errors to the exception
//! classes of `ringmesh.errors`, releases the GIL for every solve and reports
//! progress to an optional Python callable. The Python package
//! (`python/ringmesh/`) wraps these in its `Scene`, `Network` and result
//! classes.

mod convert;
mod errors;

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

use clap::ValueEnum;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use ringmesh::design::{DesignSettings, IterationRecord, RelaxationKind};
use ringmesh::network::Network;
use ringmesh::report::RmsAxis;
use ringmesh::resources::{check_scene, SceneCommand};
use ringmesh::scene::TrussModel;
use ringmesh::study::Knob;
use ringmesh::uniformity::{FrontPoint, SolverKind};

use convert::{f64_rows, f64_vector, index_array, index_rows, json_to_py, py_to_json};

/// A library result as a Python one.
trait OrRaise<T> {
    fn or_raise(self) -> PyResult<T>;
}

impl<T, E: Into<ringmesh::Error>> OrRaise<T> for Result<T, E> {
    fn or_raise(self) -> PyResult<T> {
        self.map_err(|e| errors::to_py(e.into()))
    }
}

/// One of a `clap::ValueEnum`'s names (`bisection`, `least-squares`), or a
/// `SettingError` naming `field` and the names it takes.
fn choice<T: ValueEnum>(field: &str, name: &str) -> PyResult<T> {
    T::from_str(name, true).map_err(|_| {
        let names: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value().map(|p| p.get_name().to_string()))
            .collect();
        errors::setting(
            field,
            format!("`{field}` = {name:?}: not one of {}", names.join(", ")),
        )
    })
}

/// A list of choices: one name, or a sequence of names.
fn choices<T: ValueEnum>(field: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<T>> {
    if let Ok(name) = obj.extract::<String>() {
        return name.split(',').map(|n| choice(field, n.trim())).collect();
    }
    let names: Vec<String> = obj
        .extract()
        .map_err(|_| errors::setting(field, format!("`{field}`: a name or a list of names")))?;
    names.iter().map(|n| choice(field, n)).collect()
}

/// A scene (problem file), validated by the library.
#[pyclass(frozen, module = "ringmesh._ringmesh")]
struct Scene {
    inner: ringmesh::Scene,
}

#[pymethods]
impl Scene {
    /// Reads a scene file (TOML): validated, its name the file stem unless
    /// it has one, the tables it names relative to its folder, a front net
    /// left to `[surface] rms_mm` chosen (as the CLI reads it).
    #[staticmethod]
    fn from_toml(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
        let inner = py.detach(|| ringmesh::run::read_scene(&path)).or_raise()?;
        Ok(Scene { inner })
    }

    /// A scene from TOML text (`name`: its name unless the text has one;
    /// files it names relative to `folder`).
    #[staticmethod]
    #[pyo3(signature = (text, name = "scene", folder = None))]
    fn from_toml_str(
        py: Python<'_>,
        text: &str,
        name: &str,
        folder: Option<PathBuf>,
    ) -> PyResult<Scene> {
        let folder = folder.unwrap_or_default();
        let inner = py
            .detach(|| -> Result<ringmesh::Scene, ringmesh::Error> {
                let scene = ringmesh::Scene::from_toml_in(text, name, &folder)?;
                Ok(ringmesh::surface::resolve_front_rings(&scene)?)
            })
            .or_raise()?;
        Ok(Scene { inner })
    }

    /// A scene from a dict of the problem file's tables and keys
    /// (`{"reflector": {"aperture_diameter_m": 6.0, …}, …}`), read exactly as
    /// the same TOML file would be.
    #[staticmethod]
    #[pyo3(signature = (tables, name = "scene", folder = None))]
    fn from_dict(
        py: Python<'_>,
        tables: &Bound<'_, PyDict>,
        name: &str,
        folder: Option<PathBuf>,
    ) -> PyResult<Scene> {
        let mut value = py_to_json(tables.as_any(), "", "SceneError")?;
        drop_nulls(&mut value);
        let text = toml::Value::try_from(&value)
            .and_then(|v| toml::to_string(&v))
            .map_err(|e| {
                errors::raise(
                    py,
                    "SceneError",
                    format!("the scene dict cannot be a TOML file: {e}"),
                    errors::Detail::default(),
                )
            })?;
        Scene::from_toml_str(py, &text, name, folder)
    }

    /// The scene as TOML text (what `from_toml_str` reads back).
    fn to_toml(&self) -> PyResult<String> {
        self.inner.to_toml().or_raise()
    }

    /// The scene as a dict of its tables, every key resolved (defaults
    /// included).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let value = serde_json::to_value(&self.inner).expect("a scene serialises");
        json_to_py(py, &value)
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// The scene's nets (front, rear, ties) at their design positions with
    /// their initial force densities: the fields of a network (`positions`,
    /// `edges`, `fixed`, `q`, `loads`, `groups`) and the front net's
    /// triangular `facets`, as `ringmesh mesh` writes them.
    fn mesh<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let scene = &self.inner;
        let mesh = py
            .detach(|| -> Result<_, ringmesh::Error> {
                check_scene(scene, SceneCommand::Mesh, 1)?;
                Ok(ringmesh::geometry::build_mesh(scene)?)
            })
            .or_raise()?;
        let dict = network_dict(py, mesh.network)?;
        dict.set_item("facets", index_array(py, &mesh.front_triangles)?)?;
        Ok(dict)
    }

    fn __repr__(&self) -> String {
        format!("Scene({:?})", self.inner.name)
    }
}

/// `value` with every `None` entry of a table left out (how TOML, which has
/// no null, says a key is absent).
fn drop_nulls(value: &mut serde_json::Value) {
    match value {
        serde_json::Value::Object(map) => {
            map.retain(|_, v| !v.is_null());
            map.values_mut().for_each(drop_nulls);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(drop_nulls),
        _ => {}
    }
}

/// A network's fields as a dict of numpy arrays (the vectors moved, not
/// copied; indices as int64).
fn network_dict(py: Python<'_>, n: Network) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("edges", index_array(py, &n.edges)?)?;
    d.set_item(
        "fixed",
        index_array(py, &n.fixed.iter().map(|&i| [i]).collect::<Vec<_>>())?,
    )?;
    d.set_item("positions", convert::rows_array(py, n.nodes)?)?;
    d.set_item("q", convert::vector_array(py, n.q))?;
    match n.loads {
        Some(l) => d.set_item("loads", convert::rows_array(py, l)?)?,
        None => d.set_item("loads", py.None())?,
    }
    d.set_item("groups", n.groups)?;
    Ok(d)
}

/// A network from an object with the attributes `positions`, `edges`,
/// `fixed`, `q`, `loads` (or None), `groups` (or None), checked for shape
/// and dtype here and validated by the library.
fn network_of(obj: &Bound<'_, PyAny>) -> PyResult<Network> {
    let network = arrays_of(obj)?;
    network.validate().or_raise()?;
    Ok(network)
}

/// [`network_of`] before the library's validation.
fn arrays_of(obj: &Bound<'_, PyAny>) -> PyResult<Network> {
    let get = |name: &str| obj.getattr(name);
    let optional = |name: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        let v = get(name)?;
        Ok((!v.is_none()).then_some(v))
    };
    let groups = match optional("groups")? {
        Some(g) => Some(g.extract::<Vec<String>>().map_err(|_| {
            errors::network_input("groups", "`groups` must be a sequence of str".into())
        })?),
        None => None,
    };
    let network = Network {
        nodes: f64_rows::<3>(&get("positions")?, "positions")?,
        edges: index_rows::<2>(&get("edges")?, "edges")?,
        fixed: index_rows::<1>(&get("fixed")?, "fixed")?
            .into_iter()
            .map(|[i]| i)
            .collect(),
        q: f64_vector(&get("q")?, "q")?,
        loads: optional("loads")?
            .map(|l| f64_rows::<3>(&l, "loads"))
            .transpose()?,
        groups,
    };
    Ok(network)
}

/// Parses the interchange JSON into a network dict.
#[pyfunction]
fn network_from_json<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyDict>> {
    let network: Network = serde_json::from_str(text)
        .map_err(|source| ringmesh::NetworkError::Json {
            path: "<json>".into(),
            source,
        })
        .or_raise()?;
    network.validate().or_raise()?;
    network_dict(py, network)
}

/// The interchange JSON of a network, as `ringmesh mesh` writes it (pretty,
/// with a final newline).
#[pyfunction]
fn network_to_json(network: &Bound<'_, PyAny>) -> PyResult<String> {
    let n = network_of(network)?;
    let mut text = serde_json::to_string_pretty(&n).expect("a network serialises");
    text.push('\n');
    Ok(text)
}

/// Validates a network (raises the library's error naming the field).
#[pyfunction]
fn validate_network(network: &Bound<'_, PyAny>) -> PyResult<()> {
    network_of(network).map(|_| ())
}

/// Forward equilibrium (`ringmesh fdm`): positions, lengths, forces,
/// reactions, the largest residual, and the library's own times: the
/// network's validation and the solve.
#[pyfunction]
fn fdm<'py>(py: Python<'py>, network: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    let network = arrays_of(network)?;
    let (eq, validate_s, solve_s) = py.detach(|| {
        let clock = Instant::now();
        if let Err(e) = network.validate() {
            return (Err(ringmesh::Error::from(e)), 0.0, 0.0);
        }
        let validate_s = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let solved = ringmesh::fdm::solve_network(&network).map_err(ringmesh::Error::from);
        (solved, validate_s, clock.elapsed().as_secs_f64())
    });
    let (_, eq) = eq.or_raise()?;
    let d = PyDict::new(py);
    d.set_item("max_residual", eq.max_residual_n())?;
    d.set_item("positions", convert::rows_array(py, eq.nodes_xyz_m)?)?;
    d.set_item("lengths", convert::vector_array(py, eq.edges_lengths_m))?;
    d.set_item("forces", convert::vector_array(py, eq.edges_forces_n))?;
    d.set_item("reactions", convert::rows_array(py, eq.reactions_n)?)?;
    d.set_item("validate_s", validate_s)?;
    d.set_item("solve_s", solve_s)?;
    Ok(d)
}

/// The uniformity problem on a network whose positions are the prescribed
/// geometry (`ringmesh uniformity`), the solver configured by `settings`.
#[pyfunction]
#[pyo3(signature = (network, solver = None, groups = None, mean_tension_n = None, max_force_density_n_per_m = f64::INFINITY, settings = None))]
fn uniformity<'py>(
    py: Python<'py>,
    network: &Bound<'py, PyAny>,
    solver: Option<&str>,
    groups: Option<Vec<String>>,
    mean_tension_n: Option<f64>,
    max_force_density_n_per_m: f64,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let network = network_of(network)?;
    let solver = solver
        .map(|s| choice::<SolverKind>("solver", s))
        .transpose()?;
    let settings = match settings {
        Some(s) => match py_to_json(s.as_any(), "", "SettingError")? {
            serde_json::Value::Object(m) => m,
            _ => unreachable!("a dict is an object"),
        },
        None => serde_json::Map::new(),
    };
    let output = py
        .detach(|| {
            ringmesh::run::uniformity_of(
                network,
                solver,
                &settings,
                groups.as_deref(),
                mean_tension_n,
                max_force_density_n_per_m,
            )
        })
        .or_raise()?;
    let d = PyDict::new(py);
    d.set_item("ratio", output.ratio)?;
    d.set_item("max_residual", output.max_residual)?;
    d.set_item("solver", &output.solver)?;
    d.set_item("termination", json_name(&output.termination))?;
    d.set_item("iterations", output.iterations)?;
    d.set_item("time_s", output.time_s)?;
    d.set_item("route", output.route.map(|r| r.to_string()))?;
    d.set_item("warnings", &output.warnings)?;
    d.set_item("q", convert::vector_array(py, output.q))?;
    d.set_item("tensions", convert::vector_array(py, output.tensions))?;
    Ok(d)
}

/// A value's serde name (`converged`, `lp`).
fn json_name<T: serde::Serialize + std::fmt::Debug>(v: &T) -> String {
    ringmesh::report::json_name(v)
}

/// Calls a progress callable from any thread; keeps its first error.
struct Callback {
    function: Option<Py<PyAny>>,
    error: Mutex<Option<PyErr>>,
}

impl Callback {
    fn new(function: Option<Bound<'_, PyAny>>) -> Self {
        Callback {
            function: function.map(Bound::unbind),
            error: Mutex::new(None),
        }
    }

    /// Calls the function with one dict made by `make`, the GIL taken for it.
    fn call(&self, make: impl FnOnce(Python<'_>) -> PyResult<Bound<'_, PyAny>>) {
        let Some(f) = &self.function else { return };
        Python::attach(|py| {
            let result = make(py).and_then(|arg| f.call1(py, (arg,)));
            if let Err(e) = result {
                let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
                slot.get_or_insert(e);
            }
        });
    }

    /// The first error the callable raised, if any.
    fn finish(self) -> PyResult<()> {
        match self.error.into_inner().unwrap_or_else(|p| p.into_inner()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// A serialisable value as a Python object (through its JSON).
fn to_py<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    json_to_py(py, &serde_json::to_value(v).expect("a report serialises"))
}

/// The whole design job (`ringmesh design`, without files): the report
/// (`design.json`'s content) as a dict, the network at the design's
/// geometry, the design's per-cable arrays and the cut lengths.
#[pyfunction]
#[pyo3(signature = (scene, solver = None, truss = None, relaxation = None, tolerance_m = None, max_iterations = None, progress = None))]
#[allow(clippy::too_many_arguments)]
fn design<'py>(
    py: Python<'py>,
    scene: &Scene,
    solver: Option<&str>,
    truss: Option<&str>,
    relaxation: Option<&Bound<'py, PyAny>>,
    tolerance_m: Option<f64>,
    max_iterations: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut settings = DesignSettings {
        solver: solver
            .map(|s| choice::<SolverKind>("solver", s))
            .transpose()?,
        truss: truss
            .map(|t| choice::<TrussModel>("truss", t))
            .transpose()?,
        ..DesignSettings::default()
    };
    if let Some(r) = relaxation {
        settings.relaxations = choices::<RelaxationKind>("relaxation", r)?;
    }
    if let Some(t) = tolerance_m {
        settings.tolerance_m = t;
    }
    if let Some(n) = max_iterations {
        settings.max_iterations = n;
    }
    let callback = Callback::new(progress);
    let scene = &scene.inner;
    let run = py
        .detach(|| -> Result<_, ringmesh::Error> {
            check_scene(scene, SceneCommand::Design, 1)?;
            let mut observe = |kind: RelaxationKind, r: &IterationRecord| {
                callback.call(|py| {
                    let d = to_py(py, r)?;
                    d.set_item("relaxation", kind.name())?;
                    Ok(d)
                });
            };
            Ok(ringmesh::design::run(scene, &settings, &mut observe)?)
        })
        .or_raise()?;
    callback.finish()?;
    let report = run.report;
    let cables = &scene.cables;
    let cut: Vec<f64> = report
        .net
        .lengths_m
        .iter()
        .zip(&report.net.tensions_n)
        .map(|(&l, &t)| cables.cut_length_m(l, t))
        .collect();
    let d = PyDict::new(py);
    d.set_item("report", to_py(py, &report)?)?;
    d.set_item("q", convert::vector_array(py, report.net.q.clone()))?;
    d.set_item(
        "tensions",
        convert::vector_array(py, report.net.tensions_n.clone()),
    )?;
    d.set_item(
        "lengths",
        convert::vector_array(py, report.net.lengths_m.clone()),
    )?;
    d.set_item("cut_lengths", convert::vector_array(py, cut))?;
    d.set_item(
        "positions",
        convert::rows_array(py, report.net.nodes_xyz_m.clone())?,
    )?;
    d.set_item(
        "assembled_positions",
        convert::rows_array(py, report.verification.nodes_xyz_m.clone())?,
    )?;
    d.set_item("network", network_dict(py, run.network)?)?;
    d.set_item("facets", index_array(py, &run.mesh.front_triangles)?)?;
    Ok(d)
}

/// A point of a front as a record.
fn front_record<'py>(py: Python<'py>, p: &FrontPoint) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("solver", json_name(&p.solver))?;
    d.set_item("knob", p.knob)?;
    d.set_item("ratio", p.ratio)?;
    d.set_item("rms_mm", p.rms_mm)?;
    d.set_item("time_s", p.time_s)?;
    match &p.outcome {
        Ok(t) => {
            d.set_item("termination", json_name(t))?;
            d.set_item("error", py.None())?;
        }
        Err(e) => {
            d.set_item("termination", py.None())?;
            d.set_item("error", e.to_string())?;
        }
    }
    Ok(d.into_any())
}

/// The design front (`ringmesh front`, without files): one record per point,
/// in sweep order; the facet RMS a total RMS is drawn with (or None).
#[pyfunction]
#[pyo3(signature = (scene, solvers, points, rms = "design", progress = None))]
fn front<'py>(
    py: Python<'py>,
    scene: &Scene,
    solvers: &Bound<'py, PyAny>,
    points: usize,
    rms: &str,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyList>, Option<f64>)> {
    let solvers = choices::<SolverKind>("solvers", solvers)?;
    let rms = choice::<RmsAxis>("rms", rms)?;
    let callback = Callback::new(progress);
    let scene = &scene.inner;
    let (front, drawn) = py
        .detach(|| {
            ringmesh::run::front_points(scene, &solvers, points, rms, &|p: &FrontPoint| {
                callback.call(|py| front_record(py, p));
            })
        })
        .or_raise()?;
    callback.finish()?;
    let records = PyList::empty(py);
    for p in &front {
        records.append(front_record(py, p)?)?;
    }
    let facets = match drawn {
        ringmesh::report::FrontRms::Total { facets_mm } => Some(facets_mm),
        ringmesh::report::FrontRms::Design => None,
    };
    Ok((records, facets))
}

/// The accuracy study (`ringmesh study`, without files): one record per
/// point (`index` its place in the sweep), in sweep order.
#[pyfunction]
#[pyo3(signature = (scene, knobs = None, tolerances_m = None, elements_per_rod = None, rings = None, truss_models = None, solvers = None, max_iterations = None, jobs = 1, progress = None))]
#[allow(clippy::too_many_arguments)]
fn study<'py>(
    py: Python<'py>,
    scene: &Scene,
    knobs: Option<&Bound<'py, PyAny>>,
    tolerances_m: Option<Vec<f64>>,
    elements_per_rod: Option<Vec<usize>>,
    rings: Option<Vec<usize>>,
    truss_models: Option<&Bound<'py, PyAny>>,
    solvers: Option<&Bound<'py, PyAny>>,
    max_iterations: Option<usize>,
    jobs: usize,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let mut options = ringmesh::run::StudyOptions {
        tolerances_m,
        elements_per_rod,
        rings,
        max_iterations,
        jobs,
        ..Default::default()
    };
    if let Some(k) = knobs {
        options.knobs = choices::<Knob>("knobs", k)?;
    }
    if let Some(t) = truss_models {
        options.truss_models = Some(choices::<TrussModel>("truss_models", t)?);
    }
    if let Some(s) = solvers {
        options.solvers = Some(choices::<SolverKind>("solvers", s)?);
    }
    let callback = Callback::new(progress);
    let scene = &scene.inner;
    let rows = py
        .detach(|| {
            ringmesh::run::study_rows(scene, &options, &|row| callback.call(|py| to_py(py, row)))
        })
        .or_raise()?;
    callback.finish()?;
    let records = PyList::empty(py);
    for (index, row) in &rows {
        let d = to_py(py, row)?;
        d.set_item("index", index)?;
        records.append(d)?;
    }
    Ok(records)
}

/// The native module.
#[pymodule]
fn _ringmesh(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_function(wrap_pyfunction!(network_from_json, m)?)?;
    m.add_function(wrap_pyfunction!(network_to_json, m)?)?;
    m.add_function(wrap_pyfunction!(validate_network, m)?)?;
    m.add_function(wrap_pyfunction!(fdm, m)?)?;
    m.add_function(wrap_pyfunction!(uniformity, m)?)?;
    m.add_function(wrap_pyfunction!(design, m)?)?;
    m.add_function(wrap_pyfunction!(front, m)?)?;
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
