"""Shapes of the paper's nets and the parameters the deep net shares with the shallow one."""

import pytest
import torch

from sann.nets import DeepNet, ShallowNet


def test_shallow_net_is_the_papers_15_5_2_net():
    net = ShallowNet(15)
    assert net.features[0].weight.shape == (5, 15)
    assert net.head.weight.shape == (2, 5)
    assert net(torch.zeros(7, 15)).shape == (7, 2)
    assert net.hidden(torch.zeros(7, 15)).shape == (7, 5)


def test_standard_ann_differs_only_by_the_logical_item():
    ann, sann = ShallowNet(14), ShallowNet(15)
    shapes = lambda net: [p.shape for p in net.parameters()]  # noqa: E731
    assert shapes(ann)[1:] == shapes(sann)[1:]
    assert shapes(sann)[0][1] - shapes(ann)[0][1] == 1


def test_deep_net_shares_the_shallow_nets_first_layer():
    shallow = ShallowNet(131, hidden=64)
    deep = DeepNet(131, hidden=(64, 32, 16), shallow=shallow)
    assert deep.shallow.features is shallow.features
    shared = {id(p) for p in shallow.features.parameters()}
    assert shared <= {id(p) for p in deep.parameters()}
    with torch.no_grad():
        shallow.features[0].weight.fill_(0.5)
    assert torch.all(deep.shallow.features[0].weight == 0.5)
    assert deep(torch.zeros(3, 131)).shape == (3, 2)
    head = {id(p) for p in shallow.head.parameters()}
    assert not head & {id(p) for p in deep.parameters()}, "the shallow head is not in the deep net"
    assert sum(p.numel() for p in deep.parameters()) == (
        131 * 64 + 64 + 64 * 32 + 32 + 32 * 16 + 16 + 16 * 2 + 2)
    assert deep.hidden(torch.zeros(3, 131)).shape == (3, 16)


def test_deep_net_rejects_a_shallow_net_of_the_wrong_shape():
    with pytest.raises(ValueError, match="first layer"):
        DeepNet(131, hidden=(64, 32), shallow=ShallowNet(15))
