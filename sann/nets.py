"""The paper's networks (Fig. 5): a shallow net for the block task and a deep net whose first
layer *is* the shallow net's, so both tasks share components (the paper's "shallow-deep"
module).

The standard ANN and SANN are the same architecture; SANN simply has one more input, the
logical item computed by fusion from the Soar plans.
"""

from __future__ import annotations

import torch
from torch import nn


class ShallowNet(nn.Module):
    """Input -> ``hidden`` tanh units -> 2 logits (graspable or not).

    With 15 inputs (13 block features, the image id and the logical item) and 5 hidden units
    this is the paper's SANN net for the block task; with 14 inputs it is the standard ANN.
    """

    def __init__(self, n_inputs: int, hidden: int = 5, n_outputs: int = 2) -> None:
        super().__init__()
        self.features = nn.Sequential(nn.Linear(n_inputs, hidden), nn.Tanh())
        self.head = nn.Linear(hidden, n_outputs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.features(x))

    def hidden(self, x: torch.Tensor) -> torch.Tensor:
        """Activations of the hidden layer (what Fig. 14's t-SNE looks at)."""
        return self.features(x)


class DeepNet(nn.Module):
    """A deeper classifier whose first layer is a ShallowNet's feature layer — the very same
    module, so its parameters are shared — followed by further hidden layers.

    Used for the cup task, where each image is a 10 x 13 pose array (plus the logical item
    for SANN): the shared first layer can be pre-trained as a shallow net and reused.
    """

    def __init__(
        self,
        n_inputs: int,
        hidden: tuple[int, ...] = (64, 32, 16),
        n_outputs: int = 2,
        shallow: ShallowNet | None = None,
    ) -> None:
        super().__init__()
        if not hidden:
            raise ValueError("DeepNet needs at least one hidden layer")
        if shallow is None:
            shallow = ShallowNet(n_inputs, hidden[0], n_outputs)
        # Register only the shared feature layer: the shallow net's own head is not part of
        # the deep net, so it must not count among (or be optimised with) its parameters.
        self.features = shallow.features
        object.__setattr__(self, "_shallow", shallow)
        first = shallow.features[0]
        if first.in_features != n_inputs or first.out_features != hidden[0]:
            raise ValueError(
                f"the shallow net's first layer is {first.in_features}->{first.out_features}, "
                f"the deep net needs {n_inputs}->{hidden[0]}"
            )
        layers: list[nn.Module] = []
        for width_in, width_out in zip(hidden, hidden[1:], strict=False):
            layers += [nn.Linear(width_in, width_out), nn.ReLU()]
        self.deeper = nn.Sequential(*layers)
        self.head = nn.Linear(hidden[-1], n_outputs)

    @property
    def shallow(self) -> ShallowNet:
        """The shallow net whose feature layer this deep net shares."""
        return self._shallow

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.hidden(x))

    def hidden(self, x: torch.Tensor) -> torch.Tensor:
        """Activations of the last hidden layer."""
        return self.deeper(self.features(x))
