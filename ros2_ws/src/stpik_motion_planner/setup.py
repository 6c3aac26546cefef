import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'stpik_motion_planner'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['resources/*/*']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='qtree-tamp developers',
    maintainer_email='dev@qtree-tamp.example',
    description='Cartesian sampling planner with a Set-based Task-Priority IK check, served as qtree_msgs/srv/RelocateObject.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'motion_planner_node = stpik_motion_planner.motion_planner_node:main',
        ],
    },
)
