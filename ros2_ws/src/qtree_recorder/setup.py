import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'qtree_recorder'

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
    description='Records every topic of the qtree-tamp graph to MCAP (rosbag2 conventions) and to Rerun; offline replay.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'recorder_node = qtree_recorder.recorder_node:main',
        ],
    },
)
