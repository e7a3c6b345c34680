"""Arrays cross the boundary without a Python-side loop: results are numpy
arrays that own the library's buffers (no copy on the way out), inputs are
read once and left untouched."""

import numpy as np

import ringmesh


def grid_net(side: int) -> ringmesh.Network:
    """A flat square grid of side × side nodes, unit spacing, its border fixed
    and lifted into a saddle (a 10⁵-node net for side = 317), built with numpy
    alone."""
    i, j = np.meshgrid(np.arange(side), np.arange(side), indexing="ij")
    ids = (i * side + j).ravel()
    x = i.ravel().astype(np.float64)
    y = j.ravel().astype(np.float64)
    c = (side - 1) / 2
    z = ((x - c) ** 2 - (y - c) ** 2) / side
    positions = np.column_stack([x, y, z])
    grid = ids.reshape(side, side)
    across = np.column_stack([grid[:-1, :].ravel(), grid[1:, :].ravel()])
    along = np.column_stack([grid[:, :-1].ravel(), grid[:, 1:].ravel()])
    edges = np.vstack([across, along]).astype(np.int64)
    border = (i == 0) | (j == 0) | (i == side - 1) | (j == side - 1)
    fixed = ids[border.ravel()].astype(np.int64)
    q = np.ones(len(edges))
    return ringmesh.Network(positions=positions, edges=edges, fixed=fixed, q=q)


def owns_rust_buffer(a: np.ndarray) -> bool:
    """True when the array's memory is a buffer handed over by Rust: numpy does
    not own it, and the chain of bases ends in the Rust container, not in
    another array (a copy would own its data)."""
    if a.flags.owndata:
        return False
    base = a
    while isinstance(base, np.ndarray):
        if base.flags.owndata:
            return False
        base = base.base
    return base is not None and type(base).__name__ == "PySliceContainer"


def test_a_large_fdm_round_trip_hands_over_the_results_without_a_copy():
    net = grid_net(317)
    assert net.n_nodes > 100_000
    before = {f: getattr(net, f).copy() for f in ("positions", "edges", "fixed", "q")}
    eq = ringmesh.fdm(net)
    for name in ("positions", "lengths", "forces", "reactions"):
        a = getattr(eq, name)
        assert owns_rust_buffer(a), name
        assert a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable, name
    assert eq.positions.shape == (net.n_nodes, 3)
    assert eq.lengths.shape == (net.n_edges,)
    # The inputs are read, not changed, and the results are new memory.
    for f, v in before.items():
        assert np.array_equal(getattr(net, f), v), f
    assert not np.shares_memory(eq.positions, net.positions)
    # Fixed nodes stay where they were; the solve balances the free ones.
    assert np.array_equal(eq.positions[net.fixed], net.positions[net.fixed])
    assert eq.max_residual < 1e-9 * np.abs(eq.forces).max()


def test_a_non_contiguous_view_is_read_like_its_copy():
    net = grid_net(20)
    wide = np.zeros((net.n_nodes, 6))
    wide[:, ::2] = net.positions
    view = ringmesh.Network(
        positions=wide[:, ::2], edges=net.edges, fixed=net.fixed, q=net.q
    )
    assert not view.positions.flags.c_contiguous
    assert np.array_equal(ringmesh.fdm(view).positions, ringmesh.fdm(net).positions)


def test_index_arrays_of_any_integer_dtype_are_read_alike():
    net = grid_net(20)
    small = ringmesh.Network(
        positions=net.positions,
        edges=net.edges.astype(np.int32),
        fixed=net.fixed.astype(np.uint16),
        q=net.q,
    )
    assert np.array_equal(ringmesh.fdm(small).positions, ringmesh.fdm(net).positions)


def test_mesh_arrays_are_handed_over_without_a_copy():
    from conftest import PROBLEMS

    net = ringmesh.Scene.from_toml(PROBLEMS / "paper-26m.toml").mesh()
    assert owns_rust_buffer(net.positions) and owns_rust_buffer(net.q)
