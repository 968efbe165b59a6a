r"""LSTM and GRU regression networks of seed 003 (eqs (7)-(10)), torch optional.

A single recurrent layer of ``hidden`` units (paper: 60) reads the input
sequence x_t (d features) and a linear layer maps each hidden state to the
m outputs.  The cells are PyTorch's (``torch.nn.LSTM`` / ``torch.nn.GRU``),
whose activations are the paper's: sigmoid on the gates, tanh on the
candidate state.  GRU, eqs (7)-(10) (PyTorch's form, two bias vectors):

.. math::

    r_t = \sigma(W_r x_t + b_{ir} + U_r h_{t-1} + b_{hr}) \quad (7) \qquad
    z_t = \sigma(W_z x_t + b_{iz} + U_z h_{t-1} + b_{hz}) \quad (8)

    \tilde h_t = \tanh(W_n x_t + b_{in} + r_t \odot (U_n h_{t-1} + b_{hn})) \quad (9) \qquad
    h_t = (1 - z_t) \odot \tilde h_t + z_t \odot h_{t-1} \quad (10)

LSTM: i, f, g, o = sigma, sigma, tanh, sigma of W x + b_i + U h + b_h;
c_t = f c_{t-1} + i g; h_t = o tanh(c_t).

Training (needs torch, ``pip install 'sarins-fmu[deep]'``, torch==2.13.0):
MSE loss, NAdam, truncated back-propagation through time on ``streams``
contiguous pieces of the training series read side by side in windows of
``seq_len`` samples, the hidden state carried from window to window (so the
network learns to run on an endless stream, as it does in the compensator
FMU); one optimisation step per window, ``steps`` in all (paper: 4000).

Prediction runs the whole series statefully from a zero state, with torch
when it is installed and otherwise with the numpy cells below (same
equations, float64; used by the FMU, which steps once per communication
step).  Model weights are plain arrays (npz/JSON via the compensator file).
"""

from __future__ import annotations

import numpy as np

CELLS = ("lstm", "gru")
INSTALL_HINT = ("the recurrent models (LSTM, GRU) need PyTorch: pip install 'sarins-fmu[deep]' "
                "(torch==2.13.0, CPU)")
_GATES = {"lstm": 4, "gru": 3}


def torch_available() -> bool:
    """True when torch can be imported."""
    try:
        import torch  # noqa: F401
    except ImportError:
        return False
    return True


def require_torch():
    """Import torch or raise ImportError with the install command."""
    try:
        import torch
    except ImportError:
        raise ImportError(INSTALL_HINT) from None
    return torch


def n_parameters(cell: str, n_in: int, hidden: int, n_out: int) -> int:
    """Trainable parameters of one recurrent layer (two bias vectors) plus the linear output layer."""
    g = _GATES[_check_cell(cell)]
    return g * (hidden * n_in + hidden * hidden + 2 * hidden) + hidden * n_out + n_out


def _check_cell(cell: str) -> str:
    if cell not in CELLS:
        raise ValueError(f"unknown recurrent cell {cell!r}; choose one of {', '.join(CELLS)}")
    return cell


def _sigmoid(x):
    return 0.5 * (1.0 + np.tanh(0.5 * x))


class RecurrentWeights:
    """Weights of a trained network as float64 arrays (PyTorch layout).

    ``w_ih`` (G h, d), ``w_hh`` (G h, h), ``b_ih``, ``b_hh`` (G h,),
    ``w_out`` (m, h), ``b_out`` (m,), G = 4 (LSTM, gates i f g o) or 3 (GRU,
    gates r z n).
    """

    NAMES = ("w_ih", "w_hh", "b_ih", "b_hh", "w_out", "b_out")

    def __init__(self, cell: str, arrays: dict):
        self.cell = _check_cell(cell)
        for name in self.NAMES:
            setattr(self, name, np.asarray(arrays[name], dtype=float))
        g, h = _GATES[cell], self.w_hh.shape[1]
        d, m = self.w_ih.shape[1], self.w_out.shape[0]
        shapes = {"w_ih": (g * h, d), "w_hh": (g * h, h), "b_ih": (g * h,), "b_hh": (g * h,),
                  "w_out": (m, h), "b_out": (m,)}
        for name, shape in shapes.items():
            if getattr(self, name).shape != shape:
                raise ValueError(f"recurrent weight {name} has shape {getattr(self, name).shape}, expected {shape}")
        self.hidden, self.n_in, self.n_out = h, d, m

    def arrays(self) -> dict:
        return {name: getattr(self, name) for name in self.NAMES}

    def zero_state(self, batch: int = 1):
        """Initial (h, c) state, each (batch, hidden); c unused by the GRU."""
        return np.zeros((batch, self.hidden)), np.zeros((batch, self.hidden))

    def step(self, x: np.ndarray, state):
        """One time step for a batch: x (B, d) -> outputs (B, m), new state."""
        h, c = state
        gi = x @ self.w_ih.T + self.b_ih
        gh = h @ self.w_hh.T + self.b_hh
        n = self.hidden
        if self.cell == "lstm":
            s = gi + gh
            i, f = _sigmoid(s[:, :n]), _sigmoid(s[:, n:2 * n])
            g, o = np.tanh(s[:, 2 * n:3 * n]), _sigmoid(s[:, 3 * n:])
            c = f * c + i * g  # c_t = f c_{t-1} + i g
            h = o * np.tanh(c)  # h_t = o tanh(c_t)
        else:
            r = _sigmoid(gi[:, :n] + gh[:, :n])  # eq. (7)
            z = _sigmoid(gi[:, n:2 * n] + gh[:, n:2 * n])  # eq. (8)
            cand = np.tanh(gi[:, 2 * n:] + r * gh[:, 2 * n:])  # eq. (9)
            h = (1.0 - z) * cand + z * h  # eq. (10)
        return h @ self.w_out.T + self.b_out, (h, c)

    def run(self, z: np.ndarray) -> np.ndarray:
        """Outputs (T, m) of the whole sequence z (T, d) from a zero state (numpy, one step per sample)."""
        state = self.zero_state(1)
        out = np.empty((z.shape[0], self.n_out))
        for t in range(z.shape[0]):  # inherently sequential; torch does this in C++ when installed
            y, state = self.step(z[t:t + 1], state)
            out[t] = y[0]
        return out


def _torch_module(torch, cell: str, n_in: int, hidden: int, n_out: int):
    rnn_cls = torch.nn.LSTM if cell == "lstm" else torch.nn.GRU

    class Net(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.rnn = rnn_cls(n_in, hidden, batch_first=True)
            self.out = torch.nn.Linear(hidden, n_out)

        def forward(self, x, state=None):
            y, state = self.rnn(x, state)
            return self.out(y), state

    return Net()


def _to_weights(cell: str, net) -> RecurrentWeights:
    sd = {k: v.detach().cpu().double().numpy() for k, v in net.state_dict().items()}
    return RecurrentWeights(cell, {"w_ih": sd["rnn.weight_ih_l0"], "w_hh": sd["rnn.weight_hh_l0"],
                                   "b_ih": sd["rnn.bias_ih_l0"], "b_hh": sd["rnn.bias_hh_l0"],
                                   "w_out": sd["out.weight"], "b_out": sd["out.bias"]})


def _from_weights(torch, w: RecurrentWeights):
    net = _torch_module(torch, w.cell, w.n_in, w.hidden, w.n_out)
    t = lambda a: torch.tensor(a, dtype=torch.float32)  # noqa: E731
    net.load_state_dict({"rnn.weight_ih_l0": t(w.w_ih), "rnn.weight_hh_l0": t(w.w_hh),
                         "rnn.bias_ih_l0": t(w.b_ih), "rnn.bias_hh_l0": t(w.b_hh),
                         "out.weight": t(w.w_out), "out.bias": t(w.b_out)})
    return net


def train(cell: str, z: np.ndarray, t: np.ndarray, *, hidden: int = 60, steps: int = 4000, seq_len: int = 100,
          streams: int = 32, lr: float = 2e-3, seed: int = 0, threads: int | None = None):
    """Train a recurrent network on one standardised time series.

    Parameters
    ----------
    cell : 'lstm' or 'gru'
    z : (T, d) inputs; t : (T, m) targets (both standardised)
    hidden, steps, seq_len, streams, lr : architecture and optimiser sizes
    seed : torch seed (weights initialisation)
    threads : torch intra-op threads (default: torch's)

    Returns
    -------
    weights : RecurrentWeights
    losses : (steps,) training MSE of each step
    """
    torch = require_torch()
    cell = _check_cell(cell)
    for name, value in (("hidden", hidden), ("steps", steps), ("seq_len", seq_len), ("streams", streams)):
        if int(value) < 1:
            raise ValueError(f"{name} must be at least 1, got {value}")
    n = z.shape[0]
    streams = max(1, min(int(streams), n // int(seq_len)))
    if n < seq_len:
        raise ValueError(f"the training series ({n} samples) is shorter than one window ({seq_len})")
    if threads is not None:
        if int(threads) < 1:
            raise ValueError(f"threads must be at least 1, got {threads}")
        torch.set_num_threads(int(threads))
    torch.manual_seed(int(seed))
    net = _torch_module(torch, cell, z.shape[1], int(hidden), t.shape[1])
    opt = torch.optim.NAdam(net.parameters(), lr=float(lr))
    piece = n // streams
    windows = piece // seq_len
    # (streams, windows * seq_len, d): contiguous pieces read side by side
    zs = torch.tensor(z[:streams * piece].reshape(streams, piece, -1)[:, :windows * seq_len], dtype=torch.float32)
    ts = torch.tensor(t[:streams * piece].reshape(streams, piece, -1)[:, :windows * seq_len], dtype=torch.float32)
    losses = np.empty(int(steps))
    state = None
    for k in range(int(steps)):  # one optimisation step per window
        w = k % windows
        if w == 0:
            state = None  # a new pass over the series starts from a zero state
        sl = slice(w * seq_len, (w + 1) * seq_len)
        y, state = net(zs[:, sl], state)
        loss = torch.mean((y - ts[:, sl]) ** 2)
        opt.zero_grad()
        loss.backward()
        opt.step()
        state = tuple(s.detach() for s in state) if isinstance(state, tuple) else state.detach()
        losses[k] = loss.item()
    return _to_weights(cell, net), losses


def run(weights: RecurrentWeights, z: np.ndarray) -> np.ndarray:
    """Outputs (T, m) of the whole series z (T, d) from a zero state (torch if installed, else numpy)."""
    if not torch_available():
        return weights.run(z)
    import torch

    net = _from_weights(torch, weights)
    with torch.no_grad():
        y, _ = net(torch.tensor(z[None], dtype=torch.float32))
    return y[0].double().numpy()


def save_state_dict(weights: RecurrentWeights, path) -> None:
    """Write the weights as a torch state dict of plain tensors (``torch.save``)."""
    torch = require_torch()
    torch.save({name: torch.tensor(a) for name, a in weights.arrays().items()} | {"cell": torch.tensor(
        CELLS.index(weights.cell))}, path)


def load_state_dict(path) -> RecurrentWeights:
    """Read :func:`save_state_dict` output with ``weights_only=True`` (no pickle code)."""
    torch = require_torch()
    sd = torch.load(path, weights_only=True)
    cell = CELLS[int(sd.pop("cell"))]
    return RecurrentWeights(cell, {k: v.numpy() for k, v in sd.items()})

