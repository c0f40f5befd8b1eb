"""ONNX policy files built from docs/learning.md's layout alone (onnx.helper, no nnrobust):
a = tanh(W obs + b), and files that must be refused.
"""

from pathlib import Path

import numpy as np


def linear_policy(
    path: Path, d: int, n: int, W=None, b=None, *, batched=True, dtype=np.float32, symbolic=False
) -> Path:
    """a = tanh(obs W + b): obs [batch, d] (or [d]) -> a [batch, n]; zeros by default. With
    ``symbolic`` the lengths are named dimensions ("obs", "act"), as exporters often write them."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    kind = TensorProto.FLOAT if dtype == np.float32 else TensorProto.DOUBLE
    W = np.zeros((d, n)) if W is None else np.asarray(W)
    b = np.zeros(n) if b is None else np.asarray(b)
    din, dout = ("obs", "act") if symbolic else (d, n)
    shape_in = ["batch", din] if batched else [din]
    shape_out = ["batch", dout] if batched else [dout]
    graph = helper.make_graph(
        [
            helper.make_node("MatMul", ["obs", "W"], ["h"]),
            helper.make_node("Add", ["h", "b"], ["z"]),
            helper.make_node("Tanh", ["z"], ["action"]),
        ],
        "policy",
        [helper.make_tensor_value_info("obs", kind, shape_in)],
        [helper.make_tensor_value_info("action", kind, shape_out)],
        [numpy_helper.from_array(W.astype(dtype), "W"), numpy_helper.from_array(b.astype(dtype), "b")],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return path


def nan_policy(path: Path, d: int, n: int) -> Path:
    """a = tanh(obs 0 + NaN): a network that returns NaN."""
    return linear_policy(path, d, n, b=np.full(n, np.nan))


def unknown_operator_policy(path: Path, d: int, n: int) -> Path:
    """A model whose one node is an operator of a domain onnxruntime does not know."""
    import onnx
    from onnx import TensorProto, helper

    graph = helper.make_graph(
        [helper.make_node("Dream", ["obs"], ["action"], domain="com.example.nowhere")],
        "policy",
        [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", d])],
        [helper.make_tensor_value_info("action", TensorProto.FLOAT, ["batch", n])],
    )
    model = helper.make_model(
        graph, opset_imports=[helper.make_opsetid("", 17), helper.make_opsetid("com.example.nowhere", 1)]
    )
    model.ir_version = 8
    onnx.save(model, str(path))
    return path
