from setuptools import find_packages, setup

package_name = 'jaco2_sim'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='qtree-tamp developers',
    maintainer_email='dev@qtree-tamp.example',
    description='Kinematic simulator of the Kinova Jaco2 (joint states, scene, attach/release); robot from jaco2_description, scenes from qtree_scene.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'sim_node = jaco2_sim.sim_node:main',
        ],
    },
)
