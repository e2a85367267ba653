"""A real dask.distributed LocalCluster with 2 worker processes, shared by the
fleet tests; a recording that kills its worker twice is marked failed."""
import pytest

from hdjoint.fleet.run import connect

ALLOWED_FAILURES = 1


@pytest.fixture(scope="session")
def fleet_client():
    client = connect(None, 2, ALLOWED_FAILURES)
    yield client
    cluster = client.cluster
    client.close()
    cluster.close()


@pytest.fixture
def two_workers(fleet_client):
    """The client once both workers are up (a killed one is restarted by its nanny)."""
    fleet_client.wait_for_workers(2, timeout=120)
    return fleet_client
