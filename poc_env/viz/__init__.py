"""Pictures: episode rendering, map plots and the docs' figures (matplotlib, imported lazily)."""
