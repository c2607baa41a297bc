"""The operator's own Kubernetes API calls (kopf makes the watch / list / patch calls it needs).

Every call here is listed in ``API_CALLS``; the Helm chart's RBAC grants exactly those plus
kopf's, and a unit test checks the two agree.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import kubernetes
from kubernetes.client.exceptions import ApiException
from kubernetes.config.config_exception import ConfigException

from uavtest.controller import names
from uavtest.errors import InfrastructureError

__all__ = ["API_CALLS", "Kube", "api_client"]

# (apiGroup, resource, verb) of every request the operator sends, kopf's included. kopf's scanning of
# CRDs and namespaces is off (see handlers.configure), so it needs no cluster-wide reads; API
# discovery (GET /api, /apis) is open to every authenticated user.
API_CALLS: frozenset[tuple[str, str, str]] = frozenset(
    {
        # kopf: watch the custom resources, keep its progress annotations and finalizer on them
        (names.API_GROUP, names.PLURAL, "list"),
        (names.API_GROUP, names.PLURAL, "watch"),
        (names.API_GROUP, names.PLURAL, "patch"),
        # ours: status through the /status subresource
        (names.API_GROUP, f"{names.PLURAL}/status", "patch"),
        # kopf.adopt sets blockOwnerDeletion on children: clusters that enforce owner references
        # (OwnerReferencesPermissionEnforcement) require update on the owner's finalizers
        (names.API_GROUP, f"{names.PLURAL}/finalizers", "update"),
        # a run created by hand (no spec.testSpec) flies the test's current spec: read it once
        (names.API_GROUP, names.PLURAL, "get"),
        # runs: kopf watches them (progress annotations, finalizer); ours: create one per trigger,
        # fill in a hand-made run's testSpec, write its /status, delete runs beyond the history limits
        (names.API_GROUP, names.RUN_PLURAL, "list"),
        (names.API_GROUP, names.RUN_PLURAL, "watch"),
        (names.API_GROUP, names.RUN_PLURAL, "patch"),
        (names.API_GROUP, names.RUN_PLURAL, "create"),
        (names.API_GROUP, names.RUN_PLURAL, "delete"),
        (names.API_GROUP, f"{names.RUN_PLURAL}/status", "patch"),
        (names.API_GROUP, f"{names.RUN_PLURAL}/finalizers", "update"),
        # children
        ("batch", "jobs", "list"),
        ("batch", "jobs", "watch"),
        ("batch", "jobs", "create"),
        ("", "configmaps", "create"),
        # each run's upload-policy Secret: created before its Job, read back (metadata only is used)
        # when it exists already (an operator restarted mid-start); never listed, changed or deleted
        ("", "secrets", "create"),
        ("", "secrets", "get"),
        ("", "pods", "list"),
        ("", "pods", "watch"),
        # kopf.event and kopf's own handler events
        ("", "events", "create"),
    }
)


def api_client() -> kubernetes.client.ApiClient:
    """A client for the cluster the operator runs in, else the one KUBECONFIG points at."""
    configuration = kubernetes.client.Configuration()
    try:
        kubernetes.config.load_incluster_config(client_configuration=configuration)
    except ConfigException:
        kubernetes.config.load_kube_config(client_configuration=configuration)
    return kubernetes.client.ApiClient(configuration)


class Kube:
    """Creates children (idempotently: 409 Conflict means it exists) and patches UavTest status."""

    def __init__(self, client: kubernetes.client.ApiClient) -> None:
        self._client = client
        self._core = kubernetes.client.CoreV1Api(client)
        self._batch = kubernetes.client.BatchV1Api(client)
        self._custom = kubernetes.client.CustomObjectsApi(client)

    def close(self) -> None:
        self._client.close()

    def create_configmap(self, namespace: str, body: Mapping[str, Any]) -> bool:
        """Create the ConfigMap; False when one of that name already exists."""
        try:
            self._core.create_namespaced_config_map(namespace, body)
        except ApiException as e:
            if e.status == 409:
                return False
            raise
        return True

    def create_secret(self, namespace: str, body: Mapping[str, Any]) -> bool:
        """Create the Secret; False when one of that name already exists.

        An error names the Secret and the HTTP status only: the API's answer is not passed on, so
        nothing of the Secret's data can reach a log or an Event.
        """
        name = body["metadata"]["name"]
        try:
            self._core.create_namespaced_secret(namespace, body)
        except ApiException as e:
            if e.status == 409:
                return False
            raise InfrastructureError(
                f"creating Secret {namespace}/{name} failed: HTTP {e.status} {e.reason}"
            ) from None
        return True

    def secret_metadata(self, namespace: str, name: str) -> dict[str, Any] | None:
        """The metadata of a Secret (its data is dropped unread); None when there is none."""
        try:
            secret = self._core.read_namespaced_secret(name, namespace)
        except ApiException as e:
            if e.status == 404:
                return None
            raise InfrastructureError(
                f"reading Secret {namespace}/{name} failed: HTTP {e.status} {e.reason}"
            ) from None
        return self._client.sanitize_for_serialization(secret.metadata)  # type: ignore[no-any-return]

    def create_job(self, namespace: str, body: Mapping[str, Any]) -> dict[str, Any] | None:
        """Create the Job and return it as created; None when one of that name already exists."""
        try:
            created = self._batch.create_namespaced_job(namespace, body)
        except ApiException as e:
            if e.status == 409:
                return None
            raise
        return self._client.sanitize_for_serialization(created)  # type: ignore[no-any-return]

    def _patch_status(self, plural: str, namespace: str, name: str, status: Mapping[str, Any]) -> bool:
        try:
            self._custom.patch_namespaced_custom_object_status(
                names.API_GROUP, names.VERSION, namespace, plural, name, {"status": dict(status)}
            )
        except ApiException as e:
            if e.status == 404:
                return False
            raise
        return True

    def patch_status(self, namespace: str, name: str, status: Mapping[str, Any]) -> bool:
        """Merge-patch ``status`` into the UavTestRun's /status; False when the run is gone."""
        return self._patch_status(names.RUN_PLURAL, namespace, name, status)

    def patch_test_status(self, namespace: str, name: str, status: Mapping[str, Any]) -> bool:
        """Merge-patch ``status`` into the UavTest's /status; False when the UavTest is gone."""
        return self._patch_status(names.PLURAL, namespace, name, status)

    def get_test(self, namespace: str, name: str) -> dict[str, Any] | None:
        """The UavTest ``name``; None when there is none."""
        try:
            return self._custom.get_namespaced_custom_object(  # type: ignore[no-any-return]
                names.API_GROUP, names.VERSION, namespace, names.PLURAL, name
            )
        except ApiException as e:
            if e.status == 404:
                return None
            raise

    def create_run(self, namespace: str, body: Mapping[str, Any]) -> bool:
        """Create the UavTestRun; False when one of that name already exists."""
        try:
            self._custom.create_namespaced_custom_object(
                names.API_GROUP, names.VERSION, namespace, names.RUN_PLURAL, body
            )
        except ApiException as e:
            if e.status == 409:
                return False
            raise
        return True

    def patch_run(self, namespace: str, name: str, patch: Mapping[str, Any]) -> dict[str, Any]:
        """Merge-patch a hand-made UavTestRun: its test's owner reference and label, its testSpec."""
        return self._custom.patch_namespaced_custom_object(  # type: ignore[no-any-return]
            names.API_GROUP, names.VERSION, namespace, names.RUN_PLURAL, name, dict(patch)
        )

    def delete_run(self, namespace: str, name: str) -> bool:
        """Delete the UavTestRun (its Job, pods, ConfigMap and Secret follow: owner references)."""
        try:
            self._custom.delete_namespaced_custom_object(
                names.API_GROUP,
                names.VERSION,
                namespace,
                names.RUN_PLURAL,
                name,
                body={"propagationPolicy": "Background"},
            )
        except ApiException as e:
            if e.status == 404:
                return False
            raise
        return True
