"""Following a node socket's link back to what feeds it, through reroutes: what the material
reader (``materials``) and the media reader (``volumes``) share."""


def source(socket):
    """The node and output socket feeding ``socket`` (through reroutes), or (None, None)."""
    seen = 0
    while socket is not None and socket.is_linked and seen < 64:
        link = socket.links[0]
        if not getattr(link, "is_valid", True) or getattr(link, "is_muted", False):
            return None, None
        node, out = link.from_node, link.from_socket
        if node.bl_idname == "NodeReroute":
            socket = node.inputs[0]
            seen += 1
            continue
        return node, out
    return None, None
