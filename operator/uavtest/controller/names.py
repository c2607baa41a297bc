"""Every name the operator writes into the cluster, defined once.

API group and resource, labels, annotations, container and volume names, condition types and
reasons (the status vocabulary ``Phase``, ``ConditionType``, ``ConditionReason`` comes from
``uavtest.spec.status``, which the CRD is generated from; ``Reason`` adds the operator's), Event
reasons. Condition reasons and Event reasons are CamelCase constants (Kubernetes
API conventions) and documented here, so users can match on them.
"""

from __future__ import annotations

from enum import StrEnum

from uavtest.spec.crd import RUN_KIND, RUN_PLURAL
from uavtest.spec.models import API_GROUP, API_VERSION, KIND
from uavtest.spec.status import ConditionReason, ConditionType, Phase

__all__ = [
    "API_GROUP",
    "API_VERSION",
    "CONTAINER_RUNNER",
    "CONTAINER_SITL",
    "FINALIZER",
    "JOB_INDEX_ANNOTATION",
    "JOB_INDEX_LABEL",
    "KIND",
    "LABEL_COMPONENT",
    "LABEL_INSTANCE",
    "LABEL_MANAGED_BY",
    "LABEL_NAME",
    "LABEL_PART_OF",
    "LABEL_REPLICA",
    "LABEL_RUN",
    "LABEL_TEST",
    "MANAGER",
    "PLURAL",
    "PROGRESS_PREFIX",
    "RERUN_ANNOTATION",
    "RUN_KIND",
    "RUN_PLURAL",
    "TEST_FILE",
    "TEST_MOUNT",
    "UPLOAD_EXPIRES_ANNOTATION",
    "UPLOAD_POLICY_KEY",
    "UPLOAD_PREFIX_ANNOTATION",
    "VERSION",
    "ConditionReason",
    "ConditionType",
    "EventReason",
    "Phase",
    "Reason",
    "Trigger",
]

VERSION = API_VERSION.split("/", 1)[1]
PLURAL = "uavtests"
# RUN_PLURAL "uavtestruns", RUN_KIND "UavTestRun": one run of a UavTest, owned by it

# Set it to any new value to run the test again (the value names the run: <test>-r<hash>).
RERUN_ANNOTATION = f"{API_GROUP}/rerun"

# kopf's own bookkeeping lives under our API group, not under kopf.zalando.org. Its annotations
# get a sub-domain of their own: kopf ignores every annotation under its storage prefix when it
# looks for changes, and a user's uavtest.io/rerun must count as one.
FINALIZER = f"{API_GROUP}/finalizer"
PROGRESS_PREFIX = f"operator.{API_GROUP}"

MANAGER = "uavtest-operator"

# Recommended labels (app.kubernetes.io/*) and ours (uavtest.io/*).
LABEL_NAME = "app.kubernetes.io/name"  # always "uavtest"
LABEL_INSTANCE = "app.kubernetes.io/instance"  # the test's name
LABEL_COMPONENT = "app.kubernetes.io/component"  # "replica" on Jobs, pods and ConfigMaps
LABEL_PART_OF = "app.kubernetes.io/part-of"  # "uavtest"
LABEL_MANAGED_BY = "app.kubernetes.io/managed-by"  # MANAGER
LABEL_TEST = f"{API_GROUP}/test"  # the UavTest's name: maps a Job or pod to its parent
LABEL_RUN = f"{API_GROUP}/run"  # the run id: one per UavTestRun object (its uid's head)
# The replica index of a pod. Kubernetes stamps it on Indexed Job pods itself (JOB_INDEX_LABEL);
# uavtest.io/replica is the name our metrics and docs use for the same number.
LABEL_REPLICA = f"{API_GROUP}/replica"
JOB_INDEX_LABEL = "batch.kubernetes.io/job-completion-index"
JOB_INDEX_ANNOTATION = "batch.kubernetes.io/job-completion-index"

CONTAINER_SITL = "sitl"
CONTAINER_RUNNER = "runner"

TEST_MOUNT = "/etc/uavtest"
TEST_FILE = "test.yaml"

# The run's upload Secret (<job>-upload): the signed policy under UPLOAD_POLICY_KEY; when it expires
# and where it lets replicas write, as annotations (not secret: read without decoding the policy).
UPLOAD_POLICY_KEY = "policy"
UPLOAD_EXPIRES_ANNOTATION = f"{API_GROUP}/upload-expires"
UPLOAD_PREFIX_ANNOTATION = f"{API_GROUP}/upload-prefix"


class Trigger(StrEnum):
    """Why a UavTestRun exists (its ``spec.trigger``)."""

    CREATE = "create"  # the UavTest was created
    SPEC_CHANGE = "spec-change"  # the UavTest's spec changed (a new metadata.generation)
    RERUN = "rerun"  # the uavtest.io/rerun annotation got a new value
    SCHEDULE = "schedule"  # spec.schedule came due
    MANUAL = "manual"  # created by hand (kubectl create), not by the operator


class Reason(StrEnum):
    """Condition reasons beyond the spec's ``ConditionReason`` (both are documented values)."""

    AGGREGATING = "Aggregating"  # every index finished; reading results, writing aggregate/
    STORE_UNAVAILABLE = "StoreUnavailable"  # aggregation could not reach the store; retried
    AGGREGATED = "Aggregated"  # aggregate/ written, the counts are final
    BENCH_ERRORS = "BenchErrors"  # no replica failed, but some ended in bench errors
    DEADLINE_EXCEEDED = "DeadlineExceeded"  # the Job hit activeDeadlineSeconds
    JOB_MISSING = "JobMissing"  # the Job disappeared before its replicas finished
    INVALID_SPEC = "InvalidSpec"  # the spec cannot run in a cluster (e.g. file references)
    TEST_MISSING = "TestMissing"  # a UavTestRun names a UavTest that does not exist


class EventReason(StrEnum):
    """Reasons of the Kubernetes Events the operator posts on a UavTest."""

    JOB_CREATED = "JobCreated"
    RUN_CREATED = "RunCreated"  # on a UavTest: a UavTestRun was started
    RUNS_DELETED = "RunsDeleted"  # on a UavTest: runs beyond the history limits were deleted
    TEST_PASSED = "TestPassed"
    TEST_FAILED = "TestFailed"
    FLAKY_TEST = "FlakyTest"
    REPLICA_ERROR = "ReplicaError"
    SIMULATOR_LIMITS = "SimulatorLimits"
    STORE_UNAVAILABLE = "StoreUnavailable"
    INVALID_SPEC = "InvalidSpec"
    UPLOAD_POLICY_SHORT = "UploadPolicyShort"  # the run's upload policy expires before its Job's deadline
