"""Algorithm declarations, one module per domain (see ``registry.ALGORITHM_MODULES``)."""
