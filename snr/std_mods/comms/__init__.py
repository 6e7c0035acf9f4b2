"""Communication between nodes: pipes, TCP sockets, serial links."""
