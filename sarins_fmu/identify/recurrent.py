r"""LSTM and GRU regression networks of seed 003 (eqs (7)-(10)), torch optional.

``layers`` stacked recurrent layers of ``hidden`` units each (paper: 60)
read the input sequence x_t (d features), layer l > 0 reading the hidden
state of layer l - 1, and a linear layer maps the last layer's hidden state
to the m outputs.  Seed 003 says "usually a 3-layer recurrent hidden layer
solves most problems": read as one recurrent layer between the input and
output layers (``layers=1``) or as three stacked recurrent layers
(``layers=3``); both are built.  The cells are PyTorch's
(``torch.nn.LSTM`` / ``torch.nn.GRU``, ``num_layers``), whose activations
are the paper's: sigmoid on the gates, tanh on the candidate state.  GRU,
eqs (7)-(10) (PyTorch's form, two bias vectors):

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

import contextlib

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


def n_parameters(cell: str, n_in: int, hidden: int, n_out: int, layers: int = 1) -> int:
    """Trainable parameters of ``layers`` stacked recurrent layers (two bias vectors each) plus the
    linear output layer."""
    g = _GATES[_check_cell(cell)]
    first = g * (hidden * n_in + hidden * hidden + 2 * hidden)
    later = g * (2 * hidden * hidden + 2 * hidden)
    return first + (int(layers) - 1) * later + hidden * n_out + n_out


def _check_cell(cell: str) -> str:
    if cell not in CELLS:
        raise ValueError(f"unknown recurrent cell {cell!r}; choose one of {', '.join(CELLS)}")
    return cell


def _sigmoid(x):
    return 0.5 * (1.0 + np.tanh(0.5 * x))


LAYER_NAMES = ("w_ih", "w_hh", "b_ih", "b_hh")


def _layer_key(name: str, layer: int) -> str:
    """Array name of a layer's weight: layer 0 unsuffixed (the one-layer files), then ``_l1``, ``_l2``..."""
    return name if layer == 0 else f"{name}_l{layer}"


class RecurrentWeights:
    """Weights of a trained network as float64 arrays (PyTorch layout).

    Per layer l: ``w_ih`` (G h, d for l = 0, else h), ``w_hh`` (G h, h),
    ``b_ih``, ``b_hh`` (G h,), stored as ``w_ih``, ... for layer 0 and
    ``w_ih_l1``, ... for the next; then ``w_out`` (m, h), ``b_out`` (m,).
    G = 4 (LSTM, gates i f g o) or 3 (GRU, gates r z n).
    """

    def __init__(self, cell: str, arrays: dict):
        self.cell = _check_cell(cell)
        self.layers = 1
        while _layer_key("w_ih", self.layers) in arrays:
            self.layers += 1
        try:
            self._layer = [{name: np.asarray(arrays[_layer_key(name, k)], dtype=float) for name in LAYER_NAMES}
                           for k in range(self.layers)]
            self.w_out = np.asarray(arrays["w_out"], dtype=float)
            self.b_out = np.asarray(arrays["b_out"], dtype=float)
        except KeyError as exc:
            raise ValueError(f"recurrent weights lack {exc.args[0]!r}") from None
        g, h = _GATES[cell], self._layer[0]["w_hh"].shape[-1]
        d, m = self._layer[0]["w_ih"].shape[-1], self.w_out.shape[0]
        for k, layer in enumerate(self._layer):
            shapes = {"w_ih": (g * h, d if k == 0 else h), "w_hh": (g * h, h), "b_ih": (g * h,), "b_hh": (g * h,)}
            for name, shape in shapes.items():
                if layer[name].shape != shape:
                    raise ValueError(f"recurrent weight {_layer_key(name, k)} has shape {layer[name].shape}, "
                                     f"expected {shape}")
        if self.w_out.shape != (m, h) or self.b_out.shape != (m,):
            raise ValueError(f"recurrent output weights have shapes {self.w_out.shape}, {self.b_out.shape}, "
                             f"expected {(m, h)}, {(m,)}")
        self.hidden, self.n_in, self.n_out = h, d, m

    def arrays(self) -> dict:
        out = {_layer_key(name, k): layer[name] for k, layer in enumerate(self._layer) for name in LAYER_NAMES}
        return out | {"w_out": self.w_out, "b_out": self.b_out}

    def zero_state(self, batch: int = 1):
        """Initial (h, c) state, each (layers, batch, hidden) as in PyTorch; c unused by the GRU."""
        return np.zeros((self.layers, batch, self.hidden)), np.zeros((self.layers, batch, self.hidden))

    def _cell(self, layer: dict, x, h, c):
        """One cell update of one layer: input x (B, d_l), state h, c (B, hidden) -> new h, c."""
        gi = x @ layer["w_ih"].T + layer["b_ih"]
        gh = h @ layer["w_hh"].T + layer["b_hh"]
        n = self.hidden
        if self.cell == "lstm":
            s = gi + gh
            i, f = _sigmoid(s[:, :n]), _sigmoid(s[:, n:2 * n])
            g, o = np.tanh(s[:, 2 * n:3 * n]), _sigmoid(s[:, 3 * n:])
            c = f * c + i * g  # c_t = f c_{t-1} + i g
            return o * np.tanh(c), c  # h_t = o tanh(c_t)
        r = _sigmoid(gi[:, :n] + gh[:, :n])  # eq. (7)
        z = _sigmoid(gi[:, n:2 * n] + gh[:, n:2 * n])  # eq. (8)
        cand = np.tanh(gi[:, 2 * n:] + r * gh[:, 2 * n:])  # eq. (9)
        return (1.0 - z) * cand + z * h, c  # eq. (10)

    def step(self, x: np.ndarray, state):
        """One time step for a batch: x (B, d) -> outputs (B, m), new state."""
        h, c = (np.array(a) for a in state)
        for k, layer in enumerate(self._layer):
            h[k], c[k] = self._cell(layer, x, h[k], c[k])
            x = h[k]
        return x @ self.w_out.T + self.b_out, (h, c)

    def run(self, z: np.ndarray) -> np.ndarray:
        """Outputs (T, m) of the whole sequence z (T, d) from a zero state (numpy, one step per sample)."""
        state = self.zero_state(1)
        out = np.empty((z.shape[0], self.n_out))
        for t in range(z.shape[0]):  # inherently sequential; torch does this in C++ when installed
            y, state = self.step(z[t:t + 1], state)
            out[t] = y[0]
        return out


DEVICES = ("auto", "cpu", "cuda")


def training_device(device: str = "cpu") -> str:
    """The torch device recurrent training runs on: ``'cpu'``; ``'cuda'`` or ``'cuda:N'`` (a CUDA GPU torch
    sees, else ValueError); ``'auto'``: ``'cuda'`` when torch is installed and sees a CUDA GPU, else ``'cpu'``.

    Only ``'auto'`` and the CUDA names ask torch about the GPU (which starts the CUDA driver in this process:
    resolve the device before forking fitting processes, not in them)."""
    name = str(device).strip().lower()
    kind, colon, index = name.partition(":")
    if kind not in DEVICES or (colon and (kind != "cuda" or not index.isdigit())):
        raise ValueError(f"unknown training device {device!r}; choose auto, cpu, cuda or cuda:N")
    if kind == "cpu":
        return "cpu"
    if kind == "auto" and not torch_available():
        return "cpu"
    torch = require_torch()
    count = torch.cuda.device_count() if torch.cuda.is_available() else 0
    if kind == "auto":
        return "cuda" if count else "cpu"
    if int(index or 0) >= count:
        raise ValueError(f"training device {device!r}: torch {torch.__version__} sees {count} CUDA device(s)"
                         + ("" if count else " (a CPU build, or no GPU or driver); use --device cpu"))
    return name


@contextlib.contextmanager
def _deterministic_gpu(torch, device: str):
    """cuDNN's deterministic kernels while training on a GPU (the same weights from run to run on one GPU and
    library version; not the CPU's weights: the sums are ordered differently)."""
    if device == "cpu":
        yield
        return
    before = torch.backends.cudnn.deterministic, torch.backends.cudnn.benchmark
    torch.backends.cudnn.deterministic, torch.backends.cudnn.benchmark = True, False
    try:
        yield
    finally:
        torch.backends.cudnn.deterministic, torch.backends.cudnn.benchmark = before


def _torch_module(torch, cell: str, n_in: int, hidden: int, n_out: int, layers: int = 1):
    rnn_cls = torch.nn.LSTM if cell == "lstm" else torch.nn.GRU

    class Net(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.rnn = rnn_cls(n_in, hidden, num_layers=int(layers), batch_first=True)
            self.out = torch.nn.Linear(hidden, n_out)

        def forward(self, x, state=None):
            y, state = self.rnn(x, state)
            return self.out(y), state

    return Net()


_TORCH_NAMES = {"w_ih": "weight_ih", "w_hh": "weight_hh", "b_ih": "bias_ih", "b_hh": "bias_hh"}


def _to_weights(cell: str, net) -> RecurrentWeights:
    sd = {k: v.detach().cpu().double().numpy() for k, v in net.state_dict().items()}
    arrays = {_layer_key(name, k): sd[f"rnn.{_TORCH_NAMES[name]}_l{k}"]
              for k in range(net.rnn.num_layers) for name in LAYER_NAMES}
    return RecurrentWeights(cell, arrays | {"w_out": sd["out.weight"], "b_out": sd["out.bias"]})


def _from_weights(torch, w: RecurrentWeights):
    net = _torch_module(torch, w.cell, w.n_in, w.hidden, w.n_out, w.layers)
    t = lambda a: torch.tensor(a, dtype=torch.float32)  # noqa: E731
    arrays = w.arrays()
    sd = {f"rnn.{_TORCH_NAMES[name]}_l{k}": t(arrays[_layer_key(name, k)])
          for k in range(w.layers) for name in LAYER_NAMES}
    net.load_state_dict(sd | {"out.weight": t(w.w_out), "out.bias": t(w.b_out)})
    return net


def _stream_windows(torch, series, streams: int, piece: int, length: int):
    """(streams, length, d) float32 tensor: stream s holds rows s * piece .. s * piece + length - 1 of
    ``series`` (an array, or any object with ``shape`` whose row slices are arrays), converted one stream at a
    time: the values of ``torch.tensor(series, dtype=float32)`` on those rows, without a float64 copy of the
    whole series."""
    out = torch.empty((streams, length, series.shape[1]), dtype=torch.float32)
    for s in range(streams):
        out[s] = torch.from_numpy(np.ascontiguousarray(series[s * piece:s * piece + length], dtype=float))
    return out


def train(cell: str, z: np.ndarray, t: np.ndarray, *, hidden: int = 60, layers: int = 1, steps: int = 4000,
          seq_len: int = 100, streams: int = 32, lr: float = 2e-3, seed: int = 0, threads: int | None = None,
          memory: bool = True, device: str = "cpu"):
    """Train a recurrent network on one standardised time series.

    Parameters
    ----------
    cell : 'lstm' or 'gru'
    z : (T, d) inputs; t : (T, m) targets (both standardised; arrays, or objects with ``shape`` whose row
        slices are arrays, e.g. a series standardised on demand)
    hidden, layers : units per recurrent layer and stacked recurrent layers
    steps, seq_len, streams, lr : optimiser sizes
    seed : torch seed (weights initialisation)
    threads : torch intra-op threads (default: torch's)
    memory : False trains the same network without memory (a control, not
        seed 003's method): every sample of a window is a sequence of
        length one starting from a zero state, so the network is a
        feed-forward map of the current input with the same cells, units
        and number of samples per step; predict it with ``memory=False``
    device : torch device of the training (:func:`training_device`: ``'cpu'`` default, ``'cuda'``,
        ``'cuda:N'``, ``'auto'``).  The network is initialised on the CPU (the same initial weights on
        every device) and its weights come back as float64 arrays; on a GPU the sums are ordered
        otherwise, so the weights are not the CPU's bits (docs/mems-calibration.md, *Training device*).

    Returns
    -------
    weights : RecurrentWeights
    losses : (steps,) training MSE of each step
    """
    torch = require_torch()
    cell = _check_cell(cell)
    for name, value in (("hidden", hidden), ("layers", layers), ("steps", steps), ("seq_len", seq_len),
                        ("streams", streams)):
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
    device = training_device(device)
    torch.manual_seed(int(seed))
    net = _torch_module(torch, cell, z.shape[1], int(hidden), t.shape[1], int(layers)).to(device)
    opt = torch.optim.NAdam(net.parameters(), lr=float(lr))
    piece = n // streams
    windows = piece // seq_len
    # (streams, windows * seq_len, d): contiguous pieces read side by side
    zs = _stream_windows(torch, z, streams, piece, windows * seq_len).to(device)
    ts = _stream_windows(torch, t, streams, piece, windows * seq_len).to(device)
    with _deterministic_gpu(torch, device):
        losses = _optimise(net, opt, zs, ts, int(steps), int(seq_len), windows, memory)
    return _to_weights(cell, net), losses


def _optimise(net, opt, zs, ts, steps: int, seq_len: int, windows: int, memory: bool) -> np.ndarray:
    """The training loop of :func:`train`: one NAdam step per window of every stream; the losses (steps,)."""
    import torch

    losses = np.empty(steps)
    state = None
    for k in range(steps):  # one optimisation step per window
        w = k % windows
        if w == 0:
            state = None  # a new pass over the series starts from a zero state
        sl = slice(w * seq_len, (w + 1) * seq_len)
        if memory:
            y, state = net(zs[:, sl], state)
            target = ts[:, sl]
        else:  # streams * seq_len independent one-sample sequences
            y, state = net(zs[:, sl].reshape(-1, 1, zs.shape[-1]))
            target = ts[:, sl].reshape(-1, 1, ts.shape[-1])
        loss = torch.mean((y - target) ** 2)
        opt.zero_grad()
        loss.backward()
        opt.step()
        state = tuple(s.detach() for s in state) if isinstance(state, tuple) else state.detach()
        losses[k] = loss.item()
    return losses


RUN_CHUNK = 1 << 16  # samples per forward call of :func:`run` (bounds torch's workspace: ~0.1 GB a layer)


def run(weights: RecurrentWeights, z: np.ndarray, memory: bool = True) -> np.ndarray:
    """Outputs (T, m) of the whole series z (T, d) from a zero state (torch if installed, else numpy);
    ``memory=False``: every sample from a zero state (the control of :func:`train`).

    Torch runs the series in chunks of :data:`RUN_CHUNK` samples, the state carried from one to the next:
    one call over millions of samples needs several GB of workspace, and oneDNN refuses ("could not create
    a primitive") when it cannot have it."""
    if not torch_available():
        return weights.run(z) if memory else weights.step(z, weights.zero_state(len(z)))[0]
    import torch

    net = _from_weights(torch, weights)
    out = np.empty((len(z), weights.n_out))
    state = None
    with torch.no_grad():
        for start in range(0, len(z), RUN_CHUNK):
            part = torch.tensor(z[start:start + RUN_CHUNK], dtype=torch.float32)
            if memory:
                y, state = net(part[None], state)
                out[start:start + len(part)] = y[0].double().numpy()
            else:
                y, _ = net(part[:, None])
                out[start:start + len(part)] = y[:, 0].double().numpy()
    return out


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



def training_step_seconds(cell: str, *, layers: int = 1, hidden: int = 60, n_in: int = 7, n_out: int = 6,
                          seq_len: int = 100, streams: int = 32, steps: int = 20, onednn: bool = True,
                          threads: int = 1) -> float:
    """Mean wall time of one training step as :func:`train` takes it (forward and backward over one
    window of every stream, NAdam, state carried), s, on random data.

    ``onednn``: PyTorch's oneDNN (mkldnn) RNN path on or off; since PyTorch 2.0 it runs a CPU LSTM layer
    as one fused operator, while a GRU layer is always built from per-time-step operators.
    """
    torch = require_torch()
    torch.set_num_threads(int(threads))
    torch.manual_seed(0)
    net = _torch_module(torch, _check_cell(cell), n_in, hidden, n_out, layers)
    opt = torch.optim.NAdam(net.parameters(), lr=2e-3)
    x, t = torch.randn(streams, seq_len, n_in), torch.randn(streams, seq_len, n_out)
    state = None

    def one():
        nonlocal state
        y, state = net(x, state)
        loss = torch.mean((y - t) ** 2)
        opt.zero_grad()
        loss.backward()
        opt.step()
        state = tuple(s.detach() for s in state) if isinstance(state, tuple) else state.detach()

    import time

    before = torch.backends.mkldnn.enabled  # (mkldnn.flags() would also touch the TF32 setting and warn)
    torch.backends.mkldnn.enabled = bool(onednn)
    try:
        for _ in range(3):  # warm-up: allocations, oneDNN primitive creation
            one()
        t0 = time.perf_counter()
        for _ in range(int(steps)):
            one()
        return (time.perf_counter() - t0) / int(steps)
    finally:
        torch.backends.mkldnn.enabled = before
