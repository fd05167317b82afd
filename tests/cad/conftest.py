import pytest
from cad_zoo import zoo_model


@pytest.fixture(scope="session")
def zoo():
    return zoo_model()


@pytest.fixture(scope="session")
def zoo_cad(zoo):
    from asbuilt.cad import prepare

    return prepare(zoo)
