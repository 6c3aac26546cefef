import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'jaco2_sim'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['resources/*/*']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        (os.path.join('share', package_name, 'urdf'), glob('jaco2_sim/resources/urdf/*')),
        (
            os.path.join('share', package_name, 'scenarios'),
            glob('jaco2_sim/resources/scenarios/*'),
        ),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='qtree-tamp developers',
    maintainer_email='dev@qtree-tamp.example',
    description='Kinova Jaco2 7-DoF model (URDF, Pinocchio, FCL), kinematic simulator node and the scenarios of the paper.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'sim_node = jaco2_sim.sim_node:main',
        ],
    },
)
