"""Bad input from Python raises a typed exception naming the field (scene
keys, network arrays of the wrong shape or dtype, NaN, solver settings) and
never crashes the interpreter."""

import numpy as np
import pytest

import ringmesh
from ringmesh.errors import InputError, NetworkError, SceneError, SettingError
from conftest import PROBLEMS


@pytest.fixture(scope="module")
def scene_tables():
    return ringmesh.Scene.from_toml(PROBLEMS / "small-hex.toml").to_dict()


@pytest.fixture()
def net():
    """A fresh small-hex net (tests change it)."""
    return ringmesh.Scene.from_toml(PROBLEMS / "small-hex.toml").mesh()


def test_a_scene_from_its_dict_is_the_scene_from_its_file(scene_tables):
    from_file = ringmesh.Scene.from_toml(PROBLEMS / "small-hex.toml")
    from_dict = ringmesh.Scene.from_dict(scene_tables, name="small-hex")
    assert from_dict.to_toml() == from_file.to_toml()
    again = ringmesh.Scene.from_toml_str(from_file.to_toml())
    assert again.to_dict() == from_file.to_dict()
    assert np.array_equal(from_dict.mesh().positions, from_file.mesh().positions)


def test_an_out_of_range_scene_value_names_its_key(scene_tables):
    tables = {k: dict(v) if isinstance(v, dict) else v for k, v in scene_tables.items()}
    tables["truss"]["tube_inner_diameter_m"] = tables["truss"]["tube_outer_diameter_m"] * 2
    with pytest.raises(SceneError) as e:
        ringmesh.Scene.from_dict(tables)
    assert e.value.field == "truss.tube_inner_diameter_m"
    assert "tube_inner_diameter_m" in str(e.value)
    assert isinstance(e.value, ValueError)


def test_an_unknown_scene_key_names_it(scene_tables):
    tables = {k: dict(v) if isinstance(v, dict) else v for k, v in scene_tables.items()}
    tables["truss"]["bays_typo"] = 6
    with pytest.raises(SceneError, match="bays_typo"):
        ringmesh.Scene.from_dict(tables)


def test_a_nan_scene_value_names_its_key(scene_tables):
    tables = {k: dict(v) if isinstance(v, dict) else v for k, v in scene_tables.items()}
    tables["reflector"]["focal_length_m"] = float("nan")
    with pytest.raises(InputError) as e:
        ringmesh.Scene.from_dict(tables)
    assert "focal_length_m" in str(e.value)


def test_a_missing_scene_file_is_a_scene_error(tmp_path):
    with pytest.raises(SceneError, match="nothing.toml"):
        ringmesh.Scene.from_toml(tmp_path / "nothing.toml")


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("positions", lambda n: n.positions[:, :2].copy(), r"\(n, 3\) float64"),
        ("positions", lambda n: n.positions.astype(np.float32), "float64"),
        ("positions", lambda n: n.positions.astype(np.int64), "float64"),
        ("positions", lambda n: "not an array", "positions"),
        ("edges", lambda n: n.edges.astype(np.float64), "integer"),
        ("edges", lambda n: n.edges[:, :1].copy(), r"\(m, 2\)"),
        ("q", lambda n: n.q.reshape(-1, 1), r"\(n,\) float64"),
        ("q", lambda n: n.q[:-1].copy(), "entries"),
        ("fixed", lambda n: n.fixed.astype(np.float64), "integer"),
        ("groups", lambda n: 7, "groups"),
    ],
)
def test_network_arrays_of_the_wrong_shape_or_dtype_name_the_field(net, field, value, message):
    setattr(net, field, value(net))
    for call in (ringmesh.fdm, ringmesh.uniformity, ringmesh.Network.validate):
        with pytest.raises(NetworkError, match=message) as e:
            call(net)
        assert e.value.field == field


def test_a_nan_position_names_the_field_and_node(net):
    net.positions = net.positions.copy()
    net.positions[5, 1] = np.nan
    with pytest.raises(NetworkError) as e:
        ringmesh.fdm(net)
    assert (e.value.field, e.value.node) == ("positions", 5)


def test_a_negative_force_density_names_the_cable(net):
    net.q = net.q.copy()
    net.q[3] = -1.0
    with pytest.raises(NetworkError) as e:
        ringmesh.fdm(net)
    assert (e.value.field, e.value.edge) == ("q", 3)


def test_an_edge_to_a_missing_node_names_the_cable(net):
    net.edges = net.edges.copy()
    net.edges[2, 1] = net.n_nodes + 10
    with pytest.raises(NetworkError) as e:
        ringmesh.fdm(net)
    assert (e.value.field, e.value.edge) == ("edges", 2)
    net.edges[2, 1] = -1
    with pytest.raises(NetworkError, match=r"edges\[2\]"):
        ringmesh.fdm(net)


def test_unknown_mistyped_and_out_of_range_settings_name_the_setting(net):
    with pytest.raises(SettingError) as e:
        ringmesh.uniformity(net, "bisection", epsilon=0.1)
    assert e.value.field == "epsilon"
    assert "epsilon_n" in str(e.value)  # the settings it has
    with pytest.raises(SettingError) as e:
        ringmesh.uniformity(net, "bisection", epsilon_n=-1.0)
    assert e.value.field == "epsilon_n"
    with pytest.raises(SettingError) as e:
        ringmesh.uniformity(net, "bisection", epsilon_n=float("nan"))
    assert e.value.field == "epsilon_n"
    with pytest.raises(SettingError) as e:
        ringmesh.uniformity(net, "gradient", memory=2.5)
    assert e.value.field == "memory"
    with pytest.raises(SettingError) as e:
        ringmesh.uniformity(net, "gradient", finish={"max_radius": 2.0})
    assert e.value.field == "finish.max_radius"
    with pytest.raises(SettingError) as e:
        ringmesh.uniformity(net, "lp", weight=1.0)
    assert e.value.field == "weight"
    with pytest.raises(SettingError) as e:
        ringmesh.uniformity(net, "simplex")
    assert e.value.field == "solver" and "least-squares" in str(e.value)


def test_bad_design_arguments_name_the_argument():
    scene = ringmesh.Scene.from_toml(PROBLEMS / "small-hex.toml")
    with pytest.raises(SettingError) as e:
        ringmesh.design(scene, truss="bendy")
    assert e.value.field == "truss"
    with pytest.raises(SettingError) as e:
        ringmesh.design(scene, relaxation=["anderson", "newton"])
    assert e.value.field == "relaxation"
    with pytest.raises(SettingError) as e:
        ringmesh.design(scene, tolerance_m=-1.0)
    assert "tolerance_m" in str(e.value)


def test_a_progress_callback_that_raises_surfaces_its_error():
    scene = ringmesh.Scene.from_toml(PROBLEMS / "small-hex.toml")

    def bad(record):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        ringmesh.design(scene, progress=bad)
