"""The HTTP service: post tableaux, get their maps, keep them (``bootmap serve``; docs/service.md).

``create_app(settings)`` in :mod:`bootmap.service.app` builds the FastAPI application; one router per
resource lives in :mod:`bootmap.service.routers`. Solves run in worker processes (:mod:`.worker`) with a
deadline and a memory cap; tableaux and maps are kept through SQLAlchemy (:mod:`.store`).
"""
