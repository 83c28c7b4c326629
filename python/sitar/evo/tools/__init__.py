"""evo.tools' mirror: file_interface and plot."""
