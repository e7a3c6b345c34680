//! The library's errors as Python exceptions: one class per module of
//! `ringmesh::Error` (defined in `ringmesh/errors.py`), each carrying the
//! field or node the library names, and whether the input is at fault.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use ringmesh::design::DesignError;
use ringmesh::uniformity::UniformityError;
use ringmesh::{Error, FdmError, NetworkError, SceneError};

/// What a Python exception says beyond its message.
#[derive(Debug, Default)]
pub struct Detail {
    /// The field, key or setting at fault (`truss.bays`, `positions`,
    /// `epsilon_n`).
    pub field: Option<String>,
    /// The node at fault.
    pub node: Option<usize>,
    /// The cable at fault.
    pub edge: Option<usize>,
}

/// The exception `class` of `ringmesh.errors`, raised with `message`.
pub fn raise(py: Python<'_>, class: &str, message: String, detail: Detail) -> PyErr {
    let made = (|| -> PyResult<PyErr> {
        let cls = py.import("ringmesh.errors")?.getattr(class)?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("field", detail.field)?;
        kwargs.set_item("node", detail.node)?;
        kwargs.set_item("edge", detail.edge)?;
        Ok(PyErr::from_value(cls.call((message,), Some(&kwargs))?))
    })();
    made.unwrap_or_else(|e| e)
}

/// A bad network given from Python: `field` names the attribute.
pub fn network_input(field: &str, message: String) -> PyErr {
    Python::attach(|py| {
        raise(
            py,
            "NetworkError",
            message,
            Detail {
                field: Some(field.to_string()),
                ..Detail::default()
            },
        )
    })
}

/// A bad setting given from Python: `field` names it.
pub fn setting(field: &str, message: String) -> PyErr {
    Python::attach(|py| {
        raise(
            py,
            "SettingError",
            message,
            Detail {
                field: Some(field.to_string()),
                ..Detail::default()
            },
        )
    })
}

/// The Python exception of a library error.
pub fn to_py(error: Error) -> PyErr {
    let message = error.to_string();
    let (class, detail) = classify(&error);
    Python::attach(|py| raise(py, class, message, detail))
}

/// The class and detail of a library error.
fn classify(error: &Error) -> (&'static str, Detail) {
    match error {
        Error::Scene(e) => scene(e),
        Error::Network(e) => network(e),
        Error::Fdm(e) => fdm(e),
        Error::Uniformity(e) => uniformity(e),
        Error::Design(e) => design(e),
        Error::Report(_) => ("ReportError", Detail::default()),
        Error::Truss(_) => ("TrussError", Detail::default()),
        Error::Frame(_) => ("FrameError", Detail::default()),
        Error::Verify(_) => ("VerifyError", Detail::default()),
        Error::Study(_) => ("StudyError", Detail::default()),
        Error::Sizing(_) => ("SizingError", Detail::default()),
        Error::Shard(_) => ("ShardError", Detail::default()),
        Error::Memory(_) => ("ResourceError", Detail::default()),
        Error::Surface(_) => ("SurfaceError", Detail::default()),
        Error::Budget(_) => ("BudgetError", Detail::default()),
    }
}

fn field(name: impl Into<String>) -> Detail {
    Detail {
        field: Some(name.into()),
        ..Detail::default()
    }
}

fn scene(e: &SceneError) -> (&'static str, Detail) {
    (
        "SceneError",
        Detail {
            field: e.key().map(str::to_string),
            ..Detail::default()
        },
    )
}

/// The Python attribute of an interchange-format field.
fn attribute(json_field: &str) -> &str {
    match json_field {
        "nodes" => "positions",
        other => other,
    }
}

fn network(e: &NetworkError) -> (&'static str, Detail) {
    let detail = match e {
        NetworkError::Length { field: f, .. } => field(attribute(f)),
        NetworkError::NotFinite { field: f, index } => Detail {
            field: Some(attribute(f).to_string()),
            node: Some(*index),
            edge: None,
        },
        NetworkError::EdgeOutOfRange { edge, node, .. } => Detail {
            field: Some("edges".into()),
            node: Some(*node),
            edge: Some(*edge),
        },
        NetworkError::SelfLoop { edge, node } => Detail {
            field: Some("edges".into()),
            node: Some(*node),
            edge: Some(*edge),
        },
        NetworkError::FixedOutOfRange { node, .. } | NetworkError::FixedTwice { node } => Detail {
            field: Some("fixed".into()),
            node: Some(*node),
            edge: None,
        },
        NetworkError::NoFreeNode { .. } => field("fixed"),
        NetworkError::DuplicateEdge { second, .. } => Detail {
            field: Some("edges".into()),
            edge: Some(*second),
            node: None,
        },
        NetworkError::CoincidentNodes { second, .. } => Detail {
            field: Some("positions".into()),
            node: Some(*second),
            edge: None,
        },
        NetworkError::SubnormalQ { edge, .. } | NetworkError::NonPositiveQ { edge, .. } => Detail {
            field: Some("q".into()),
            edge: Some(*edge),
            node: None,
        },
        NetworkError::QSpread { min_edge, .. } => Detail {
            field: Some("q".into()),
            edge: Some(*min_edge),
            node: None,
        },
        NetworkError::Unanchored { nodes, .. } => Detail {
            field: Some("fixed".into()),
            node: nodes.first().copied(),
            edge: None,
        },
        NetworkError::Io { .. } | NetworkError::Json { .. } | NetworkError::Empty { .. } => {
            Detail::default()
        }
    };
    ("NetworkError", detail)
}

fn fdm(e: &FdmError) -> (&'static str, Detail) {
    match e {
        FdmError::InvalidNetwork(e) => network(e),
        FdmError::Shape { field: f, .. } => ("NetworkError", field(attribute(f))),
        FdmError::InvalidQ { edge, .. } => (
            "NetworkError",
            Detail {
                field: Some("q".into()),
                edge: Some(*edge),
                node: None,
            },
        ),
        FdmError::NonFinite { node } => (
            "FdmError",
            Detail {
                node: Some(*node),
                ..Detail::default()
            },
        ),
        _ => ("FdmError", Detail::default()),
    }
}

fn uniformity(e: &UniformityError) -> (&'static str, Detail) {
    match e {
        UniformityError::Setting { name, .. } => ("SettingError", field(*name)),
        UniformityError::SettingValue { name, .. } => ("SettingError", field(name.clone())),
        UniformityError::Invalid { item, .. } => ("UniformityError", field(item.clone())),
        UniformityError::Fdm(e) => fdm(e),
        _ => ("UniformityError", Detail::default()),
    }
}

fn design(e: &DesignError) -> (&'static str, Detail) {
    match e {
        DesignError::Setting { key, .. } => ("SettingError", field(*key)),
        DesignError::Scene(e) => scene(e),
        DesignError::Problem(e) | DesignError::Uniformity { source: e, .. } => uniformity(e),
        DesignError::Truss { .. } | DesignError::RingTruss(_) => ("TrussError", Detail::default()),
        DesignError::Verify(_) => ("VerifyError", Detail::default()),
        DesignError::Surface(_) => ("SurfaceError", Detail::default()),
        DesignError::NoDesign { .. } => ("DesignError", Detail::default()),
    }
}
