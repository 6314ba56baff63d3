"""The node registry and networks from Python dicts."""
import numpy as np
import pytest

import lodestone


def test_registry_lists_every_node_with_params_and_ports():
    nodes = lodestone.node_types()
    types = [n["type"] for n in nodes]
    assert len(types) == len(set(types)) and "magnetic_force" in types and "magnet" in types
    magnet = lodestone.node_type("magnet")
    names = {p["name"] for p in magnet["params"]}
    assert "shape" in names
    assert all({"name", "type", "unit", "help", "default"} <= set(p) for p in magnet["params"])
    assert [o["type"] for o in magnet["outputs"]] == ["sources"]


def network_doc(law="paper"):
    return {
        "nodes": [
            {"name": "mat", "type": "material",
             "params": {"name": "ferro", "model": "solid", "density": 1000, "youngs_modulus": 1e5,
                        "magnetic": {"law": law}}},
            {"name": "ball", "type": "particle_source",
             "params": {"shape": "sphere", "radius": 0.01, "center": [0, 0, 0.02], "cell_size": 0.004}},
            {"name": "mag", "type": "magnet",
             "params": {"shape": "cylinder", "radius": 0.01, "half_length": 0.005, "center": [0, 0, -0.01],
                        "magnetization": 8e5}},
            {"name": "dens", "type": "magnetization_transfer", "params": {"dx": 0.004}},
            {"name": "solve", "type": "field_solve", "params": {}},
            {"name": "force", "type": "magnetic_force", "params": {}},
        ],
        "connections": [
            {"from": "mat", "output": "material", "to": "ball", "input": "material"},
            {"from": "ball", "output": "particles", "to": "dens", "input": "particles"},
            {"from": "dens", "output": "density", "to": "solve", "input": "density"},
            {"from": "mag", "output": "sources", "to": "solve", "input": "sources"},
            {"from": "solve", "output": "field", "to": "force", "input": "field"},
            {"from": "ball", "output": "particles", "to": "force", "input": "particles"},
        ],
    }


def test_network_from_dict_cooks_forces():
    net = lodestone.Network.from_dict(network_doc())
    assert set(net.node_names()) == {"mat", "ball", "mag", "dens", "solve", "force"}
    forces = net.cook("force")["forces"]
    assert forces["type"] == "forces"
    particles = net.cook("ball")["particles"]
    assert len(particles["positions"]) == len(forces["forces"])
    field = net.cook("solve")["field"]
    assert isinstance(field["stage"], lodestone.MagneticForceStage) and field["report"].converged
    assert forces["forces"].shape[1] == 3 and len(forces["forces"]) > 10
    # The ball above the magnet is pulled down; the per-particle forces sum to the total.
    assert forces["total"][2] < 0
    np.testing.assert_allclose(forces["forces"].sum(axis=0), forces["total"], rtol=1e-9,
                               atol=1e-12 * np.abs(forces["total"]).max())
