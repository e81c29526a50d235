"""Pictures: episode rendering, map plots and the README's figures (matplotlib, imported lazily)."""
