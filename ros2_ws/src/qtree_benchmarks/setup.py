from setuptools import find_packages, setup

package_name = 'qtree_benchmarks'

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
    description='Benchmarks, reference planners, reports and tools of qtree-tamp (the paper tables, the motion-planner, scale, execution and replanning benchmarks, the demo, soak and load test); no node of the product imports it.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'benchmark = qtree_benchmarks.cli.benchmark:main',
            'demo = qtree_benchmarks.cli.run_demo:main',
        ],
    },
)
