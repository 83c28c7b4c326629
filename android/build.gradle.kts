// Android library module `io.github.sitar`: the Kotlin wrapper and libsitar.so.
//
// The Android Gradle plugin and Kotlin versions come from the build that includes
// this module (an app applies them already); built on its own, the versions are in
// settings.gradle.kts. `./gradlew publishReleasePublicationToLocalRepository` writes
// the AAR to build/repo (`publishToMavenLocal` to ~/.m2).
plugins {
    id("com.android.library")
    id("org.jetbrains.kotlin.android")
    `maven-publish`
}

android {
    namespace = "io.github.sitar"
    compileSdk = 34

    defaultConfig {
        minSdk = 24
        consumerProguardFiles("consumer-rules.pro")
    }

    sourceSets["main"].jniLibs.srcDirs("src/main/jniLibs")

    compileOptions {
        sourceCompatibility = JavaVersion.VERSION_1_8
        targetCompatibility = JavaVersion.VERSION_1_8
    }
    kotlinOptions {
        jvmTarget = "1.8"
    }

    publishing {
        singleVariant("release") {
            withSourcesJar()
        }
    }
}

/** The repository root: the Cargo workspace that builds libsitar.so. */
val workspace: File = projectDir.parentFile

/**
 * The NDK cargo-ndk should use: ANDROID_NDK_HOME, ANDROID_NDK_ROOT, local.properties'
 * ndk.dir, else the newest NDK under the SDK (sdk.dir, ANDROID_HOME, ANDROID_SDK_ROOT).
 */
fun findNdk(): File? {
    val local = java.util.Properties()
    val props = rootProject.file("local.properties")
    if (props.isFile) props.inputStream().use { local.load(it) }
    listOf(System.getenv("ANDROID_NDK_HOME"), System.getenv("ANDROID_NDK_ROOT"), local.getProperty("ndk.dir"))
        .filterNotNull()
        .map { File(it) }
        .firstOrNull { it.isDirectory }
        ?.let { return it }
    return listOf(local.getProperty("sdk.dir"), System.getenv("ANDROID_HOME"), System.getenv("ANDROID_SDK_ROOT"))
        .filterNotNull()
        .map { File(it, "ndk") }
        .filter { it.isDirectory }
        .flatMap { it.listFiles()?.toList() ?: emptyList() }
        .filter { File(it, "source.properties").isFile }
        .maxByOrNull { it.name }
}

/**
 * The version of rustls-platform-verifier's Kotlin component (Maven `rustls:rustls-platform-verifier`):
 * that of the `rustls-platform-verifier-android` crate in the workspace's Cargo.lock, which the
 * verifier's Rust side (in libsitar.so) is built against; another version may not match its JNI
 * calls. Read lazily, so a changed lock file is picked up (and the configuration cache kept).
 */
val rustlsPlatformVerifierVersion: Provider<String> =
    providers.fileContents(layout.projectDirectory.file("../Cargo.lock")).asText.map { lock ->
        val lines = lock.lines()
        val at = lines.indexOfFirst { it.trim() == "name = \"rustls-platform-verifier-android\"" }
        require(at >= 0) { "rustls-platform-verifier-android not found in Cargo.lock" }
        lines[at + 1].trim().removePrefix("version = \"").removeSuffix("\"")
    }

dependencies {
    // Android's certificate verifier for unpinned https (Sitar.init(context)); libsitar.so calls
    // it over JNI. Its Maven repository (the `rustls` group only) is declared in
    // settings.gradle.kts; an app that includes this module declares it in its own settings
    // (README.md, "HTTPS").
    implementation(rustlsPlatformVerifierVersion.map { "rustls:rustls-platform-verifier:$it" })
}

val cargoNdk by tasks.registering(Exec::class) {
    description = "Builds libsitar.so for arm64-v8a, armeabi-v7a and x86_64 with cargo-ndk."
    group = "build"
    workingDir = projectDir
    // Up to date (skipped) while neither the Rust sources of sitar-ffi and its crates nor the
    // lock file nor the Android link flags (.cargo/config.toml: 16 KB pages) changed and the
    // libraries are in place.
    inputs.files(
        fileTree(workspace.resolve("rust")) {
            include("ffi/**", "core/**", "client/**")
            exclude("**/target/**")
        }
    ).withPropertyName("rustSources")
    inputs.files(workspace.resolve("Cargo.toml"), workspace.resolve("Cargo.lock"), workspace.resolve(".cargo/config.toml"))
        .withPropertyName("cargoManifests")
    outputs.dir("src/main/jniLibs").withPropertyName("jniLibs")
    commandLine(
        "cargo", "ndk",
        "-t", "arm64-v8a", "-t", "armeabi-v7a", "-t", "x86_64",
        "-o", "src/main/jniLibs",
        "build", "--release", "-p", "sitar-ffi",
    )
    doFirst {
        val ndk = findNdk()
            ?: throw GradleException("cargoNdk: no Android NDK found; set ANDROID_NDK_HOME to the NDK folder (r27 or later, e.g. \$ANDROID_HOME/ndk/27.2.12479018)")
        environment("ANDROID_NDK_HOME", ndk.path)
    }
}

tasks.named("preBuild") {
    dependsOn(cargoNdk)
}

publishing {
    publications {
        register<MavenPublication>("release") {
            groupId = "io.github.sitar"
            artifactId = "sitar"
            version = "0.1.0"
            afterEvaluate {
                from(components["release"])
            }
        }
    }
    repositories {
        maven {
            name = "local"
            url = uri(layout.buildDirectory.dir("repo"))
        }
    }
}
